#include "ipc/shm/pose_text.h"

#include <cinttypes>
#include <cstdio>

#include "core/json_text.h"
#include "core/units.h"

namespace ceilpose {

namespace {

std::string format(const char* fmt, auto... args) {
  char buffer[512];
  const int n = std::snprintf(buffer, sizeof buffer, fmt, args...);
  return std::string(buffer,
                     n < 0 ? 0 : std::min<size_t>(static_cast<size_t>(n), sizeof buffer - 1));
}

double age_ms(const PoseRecord& p, int64_t now_mono_ns) {
  return static_cast<double>(now_mono_ns - p.publish_mono_ns) / 1e6;
}

double degrees(double rad) { return rad * kDegPerRad; }

}  // namespace

std::string pose_json(const PoseRecord& p, int64_t now_mono_ns, const std::string& extra) {
  // A record some other writer filled with NaN is shown as no pose: JSON has
  // no NaN, and a controller must not act on it.
  const bool valid = pose_is_valid(p) && pose_numbers_finite(p);
  std::string out = format("{\"seq\":%" PRIu64 ",\"valid\":%s", p.seq, valid ? "true" : "false");
  const Pose2D pose{p.x_m, p.y_m, p.yaw_rad};
  out += pose_fields_json(valid ? &pose : nullptr);
  out += format(",\"mode\":\"%s\",\"markers\":%u,\"timestamp_ns\":%" PRId64
                ",\"capture_real_ns\":%" PRId64 ",\"publish_real_ns\":%" PRId64
                ",\"age_ms\":%.3f,\"filtered\":%s,\"coasting\":%s",
                pose_mode_name(p.mode), static_cast<unsigned>(p.markers), p.capture_mono_ns,
                p.capture_real_ns, p.publish_real_ns, age_ms(p, now_mono_ns),
                (p.flags & kPoseFiltered) != 0 ? "true" : "false",
                (p.flags & kPoseCoasting) != 0 ? "true" : "false");
  if (valid) {
    const double* c = p.covariance;
    out += format(",\"cov\":[%.3e,%.3e,%.3e,%.3e,%.3e,%.3e]", c[0], c[1], c[2], c[4], c[5], c[8]);
  } else {
    out += ",\"cov\":null";
  }
  if (valid && (p.flags & kPoseMotion) != 0) {
    const double* v = p.state_covariance;
    constexpr int n = CEILPOSE_STATE_SIZE;
    out += format(
        ",\"vx_mps\":%.6f,\"vy_mps\":%.6f,\"yaw_rate_radps\":%.6f,\"velocity_cov\":[%.3e,%.3e,%.3e,"
        "%.3e,%.3e,%.3e]",
        p.vx_mps, p.vy_mps, p.yaw_rate_radps, v[3 * n + 3], v[3 * n + 4], v[3 * n + 5],
        v[4 * n + 4], v[4 * n + 5], v[5 * n + 5]);
  }
  return out + extra + "}";
}

std::string no_pose_json(const std::string& extra) {
  return "{\"seq\":null,\"valid\":false" + pose_fields_json(nullptr) +
         ",\"mode\":null,\"markers\":null,\"timestamp_ns\":null" + extra + "}";
}

std::string pose_line(const PoseRecord& p, int64_t now_mono_ns) {
  if (!pose_is_valid(p)) {
    return format("seq %" PRIu64 "  no fix  mode %s  markers %u  age %.1f ms", p.seq,
                  pose_mode_name(p.mode), static_cast<unsigned>(p.markers), age_ms(p, now_mono_ns));
  }
  return format("seq %" PRIu64
                "  x %.4f m  y %.4f m  yaw %.2f deg  mode %s  markers %u  age %.1f ms",
                p.seq, p.x_m, p.y_m, degrees(p.yaw_rad), pose_mode_name(p.mode),
                static_cast<unsigned>(p.markers), age_ms(p, now_mono_ns));
}

std::string pose_table_header() {
  return format("%10s %10s %10s %9s %-11s %7s %9s %8s", "seq", "x_m", "y_m", "yaw_deg", "mode",
                "markers", "age_ms", "flags");
}

std::string pose_table_row(const PoseRecord& p, int64_t now_mono_ns) {
  std::string flags;
  if ((p.flags & kPoseFiltered) != 0) flags += "F";
  if ((p.flags & kPoseCoasting) != 0) flags += "C";
  if (!pose_is_valid(p)) {
    return format("%10" PRIu64 " %10s %10s %9s %-11s %7u %9.1f %8s", p.seq, "-", "-", "-",
                  pose_mode_name(p.mode), static_cast<unsigned>(p.markers), age_ms(p, now_mono_ns),
                  "nofix");
  }
  return format("%10" PRIu64 " %10.4f %10.4f %9.2f %-11s %7u %9.1f %8s", p.seq, p.x_m, p.y_m,
                degrees(p.yaw_rad), pose_mode_name(p.mode), static_cast<unsigned>(p.markers),
                age_ms(p, now_mono_ns), flags.c_str());
}

std::string fixed_text(double v, int decimals) { return format("%.*f", decimals, v); }

std::string duration_text(int64_t ns) {
  if (ns < 0) ns = 0;
  const int64_t s = ns / 1'000'000'000;
  if (s < 60) return format("%.1fs", static_cast<double>(ns) / 1e9);
  const int64_t d = s / 86400;
  const int64_t h = (s / 3600) % 24;
  const int64_t m = (s / 60) % 60;
  if (d > 0) return format("%" PRId64 "d%02" PRId64 "h%02" PRId64 "m", d, h, m);
  return format("%" PRId64 "h%02" PRId64 "m%02" PRId64 "s", s / 3600, m, s % 60);
}

}  // namespace ceilpose
