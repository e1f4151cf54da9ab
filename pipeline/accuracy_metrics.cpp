#include "pipeline/accuracy_metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace ceilpose {
namespace {

constexpr double kWithinUnits = 0.05;  // SPEC §6 thesis criterion
constexpr double kGrossUnits = 0.25;
constexpr double kGrossYawRad = 5.0 * std::numbers::pi / 180.0;

// Nearest-rank percentile of a sorted sample.
double percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return 0.0;
  const size_t rank = static_cast<size_t>(std::ceil(p * static_cast<double>(sorted.size())));
  return sorted[std::clamp<size_t>(rank, 1, sorted.size()) - 1];
}

}  // namespace

void AccuracyAccumulator::add(const Pose2D& truth, bool whole, const PoseEstimate& est) {
  ++counts_.frames;
  if (whole) ++counts_.frames_with_whole;
  if (!est.valid) return;
  ++counts_.valid;
  if (whole) {
    ++counts_.valid_with_whole;
  } else {
    ++counts_.valid_without_whole;
  }
  ++counts_.mode_count[static_cast<int>(est.mode) & 3];
  const double dx = std::abs(est.pose.x_m - truth.x_m) / grid_m_;
  const double dy = std::abs(est.pose.y_m - truth.y_m) / grid_m_;
  within_x_ += dx <= kWithinUnits ? 1 : 0;
  within_y_ += dy <= kWithinUnits ? 1 : 0;
  within_both_ += dx <= kWithinUnits && dy <= kWithinUnits ? 1 : 0;
  const double err_m = std::hypot(est.pose.x_m - truth.x_m, est.pose.y_m - truth.y_m);
  const double yaw_err = std::abs(wrap_angle_rad(est.pose.yaw_rad - truth.yaw_rad));
  if (err_m > kGrossUnits * grid_m_ || yaw_err > kGrossYawRad) ++counts_.gross;
  error_m_.push_back(err_m);
  yaw_error_rad_.push_back(yaw_err);
}

AccuracyReport AccuracyAccumulator::report() const {
  AccuracyReport r = counts_;
  r.availability =
      r.frames_with_whole > 0 ? static_cast<double>(r.valid_with_whole) / r.frames_with_whole : 1.0;
  if (r.valid > 0) {
    r.within_both = static_cast<double>(within_both_) / r.valid;
    r.within_x = static_cast<double>(within_x_) / r.valid;
    r.within_y = static_cast<double>(within_y_) / r.valid;
  }
  std::vector<double> e = error_m_, y = yaw_error_rad_;
  std::sort(e.begin(), e.end());
  std::sort(y.begin(), y.end());
  constexpr double kDeg = 180.0 / std::numbers::pi;
  r.median_error_mm = 1000.0 * percentile(e, 0.5);
  r.p99_error_mm = 1000.0 * percentile(e, 0.99);
  r.max_error_mm = e.empty() ? 0.0 : 1000.0 * e.back();
  r.yaw_p99_deg = kDeg * percentile(y, 0.99);
  r.yaw_max_deg = y.empty() ? 0.0 : kDeg * y.back();
  return r;
}

std::string format_report_row(const std::string& name, const AccuracyReport& r) {
  char line[320];
  std::snprintf(line, sizeof line, "| %s | %.2f%% (%d/%d) | %.2f%% | %.2f / %.2f mm | %.3f° | %d |",
                name.c_str(), 100.0 * r.availability, r.valid_with_whole, r.frames_with_whole,
                100.0 * r.within_both, r.median_error_mm, r.p99_error_mm, r.yaw_p99_deg, r.gross);
  return line;
}

}  // namespace ceilpose
