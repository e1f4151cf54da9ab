#pragma once
// Text forms of the segment's records for ceilposectl (pose, watch, status):
// JSON with the SPEC §7 field names, and one-line human summaries.
#include <cstdint>
#include <string>

#include "core/json_text.h"
#include "ipc/shm/pose_record.h"

namespace ceilpose {

// One JSON object, no newline: seq, valid, x_m, y_m, yaw_rad (null when
// invalid), mode, markers, timestamp_ns (capture, CLOCK_MONOTONIC, as SPEC §4),
// then capture_real_ns, publish_real_ns, age_ms, filtered, coasting and cov
// (upper triangle xx, xy, xyaw, yy, yyaw, yawyaw; null when invalid), and
// with the filter's motion vx_mps, vy_mps, yaw_rate_radps and velocity_cov
// (the same upper triangle of the rates).
// `extra` (e.g. ",\"daemon\":\"stale\"") is appended inside the braces.
std::string pose_json(const PoseRecord& pose, int64_t now_mono_ns, const std::string& extra = "");
// The same fields, all null, for "no pose" answers.
std::string no_pose_json(const std::string& extra = "");

// "seq 12  x 1.2345 m  y -0.5000 m  yaw  30.00 deg  mode lsq  markers 9  age 12.3 ms"
std::string pose_line(const PoseRecord& pose, int64_t now_mono_ns);
// Column header matching pose_table_row().
std::string pose_table_header();
std::string pose_table_row(const PoseRecord& pose, int64_t now_mono_ns);

// `v` with `decimals` digits after the point ("12.3").
std::string fixed_text(double v, int decimals);

// "1h02m03s"
std::string duration_text(int64_t ns);

}  // namespace ceilpose
