#include "daemon/pose_printer.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string_view>

#include "core/units.h"
#include "daemon/nonblocking_write.h"

namespace ceilpose::daemon {

std::string status_line(const PoseSnapshot& s, const capture::FrameLatency& latency) {
  const capture::LatencySummary lat = latency.dequeue_to_published().summary();
  char buf[200];
  std::snprintf(buf, sizeof(buf), "fix %s, %d markers, %.1f fps, latency p50 %.2f ms p99 %.2f ms",
                to_string(s.fix), s.markers, s.fps, static_cast<double>(lat.p50_us) / 1000.0,
                static_cast<double>(lat.p99_us) / 1000.0);
  return buf;
}

std::string pose_line(const PoseSnapshot& s, int64_t start_ns) {
  const double t_s = static_cast<double>(s.capture_ns - start_ns) * 1e-9;
  char line[320];
  int n = 0;
  if (s.valid) {
    n = std::snprintf(
        line, sizeof(line), "t=%8.3f s  x=%8.4f m  y=%8.4f m  yaw=%8.2f deg  %-11s %2d markers",
        t_s, s.pose.x_m, s.pose.y_m, s.pose.yaw_rad * kDegPerRad,
        s.fix == FixState::kCoasting ? "coasting" : std::string(to_string(s.mode)).c_str(),
        s.markers);
  } else {
    const std::string_view why = to_string(s.refusal);
    n = std::snprintf(line, sizeof(line), "t=%8.3f s  no pose (%s: %.*s)%*s %2d markers", t_s,
                      to_string(s.fix), static_cast<int>(why.size()), why.data(), 16, "",
                      s.markers);
  }
  if (s.has_ground_truth && n > 0 && n < static_cast<int>(sizeof(line))) {
    const Pose2D& g = s.ground_truth;
    n += std::snprintf(line + n, sizeof(line) - n, "  | truth x=%8.4f y=%8.4f yaw=%8.2f", g.x_m,
                       g.y_m, g.yaw_rad * kDegPerRad);
    if (s.valid && n < static_cast<int>(sizeof(line))) {
      const double err_mm = 1000.0 * std::hypot(s.pose.x_m - g.x_m, s.pose.y_m - g.y_m);
      const double yaw_err = wrap_angle_rad(s.pose.yaw_rad - g.yaw_rad) * kDegPerRad;
      n += std::snprintf(line + n, sizeof(line) - n, "  err %6.1f mm %6.2f deg", err_mm, yaw_err);
    }
  }
  if (n > 0 && n < static_cast<int>(sizeof(line)))
    std::snprintf(line + n, sizeof(line) - n, "  | latency %.2f ms",
                  static_cast<double>(s.latency_ns) * 1e-6);
  return std::string(line) + "\n";
}

void PosePrinter::print(const PoseSnapshot& s) {
  if (stopped_) return;
  const std::string line = pose_line(s, start_ns_);
  switch (write_without_blocking(STDOUT_FILENO, line.data(), line.size())) {
    case WriteOutcome::kWritten:
      ++printed_;
      return;
    case WriteOutcome::kDropped:
      if (dropped_++ == 0)
        spdlog::warn(
            "--print-poses: stdout is not being read; pose lines are dropped, not waited for");
      return;
    case WriteOutcome::kClosed:
      stopped_ = true;
      spdlog::warn("--print-poses: stdout was closed by its reader after {} lines; printing stops",
                   printed_);
      return;
    case WriteOutcome::kFailed:
      stopped_ = true;
      spdlog::warn("--print-poses: cannot write to stdout ({}) after {} lines; printing stops",
                   std::strerror(errno), printed_);
      return;
  }
}

PosePrinter::~PosePrinter() {
  if (dropped_ > 0)
    spdlog::warn("--print-poses: {} pose lines dropped because stdout was not read ({} printed)",
                 dropped_, printed_);
}

}  // namespace ceilpose::daemon
