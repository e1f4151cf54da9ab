#pragma once
// The text ceilposed shows people: one line per pose for --print-poses (with
// the source's ground truth and error when it knows them) and the systemd
// STATUS= line. Control thread only.
#include <cstdint>
#include <string>

#include "capture/latency_histogram.h"
#include "daemon/pipeline_worker.h"

namespace ceilpose::daemon {

// "fix fix, 9 markers, 30.0 fps, latency p50 0.41 ms p99 0.62 ms"
std::string status_line(const PoseSnapshot& s, const capture::FrameLatency& latency);

// Prints one --print-poses line for `s` (times relative to start_ns) and
// flushes stdout.
void print_pose(const PoseSnapshot& s, int64_t start_ns);

}  // namespace ceilpose::daemon
