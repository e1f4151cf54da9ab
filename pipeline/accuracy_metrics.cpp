#include "pipeline/accuracy_metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/units.h"

namespace ceilpose {
namespace {

constexpr double kWithinUnits = 0.05;  // SPEC §6 thesis criterion
constexpr double kGrossUnits = 0.25;
constexpr double kGrossYawRad = 5.0 * kRadPerDeg;

// e^T C^-1 e for a 3x3 symmetric covariance; negative when C is singular.
double nees(const std::array<double, 9>& c, double ex, double ey, double eyaw) {
  const double a = c[0], b = c[1], d = c[2], e = c[4], f = c[5], g = c[8];
  const double c00 = e * g - f * f, c01 = d * f - b * g, c02 = b * f - d * e;
  const double det = a * c00 + b * c01 + d * c02;
  if (!(det > 0.0)) return -1.0;
  const double c11 = a * g - d * d, c12 = b * d - a * f, c22 = a * e - b * b;
  const double q = c00 * ex * ex + c11 * ey * ey + c22 * eyaw * eyaw +
                   2.0 * (c01 * ex * ey + c02 * ex * eyaw + c12 * ey * eyaw);
  return q / det;
}

}  // namespace

double percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return 0.0;
  const size_t rank = static_cast<size_t>(std::ceil(p * static_cast<double>(sorted.size())));
  return sorted[std::clamp<size_t>(rank, 1, sorted.size()) - 1];
}

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
  const double q = nees(est.covariance, est.pose.x_m - truth.x_m, est.pose.y_m - truth.y_m,
                        wrap_angle_rad(est.pose.yaw_rad - truth.yaw_rad));
  if (q >= 0.0) nees_.push_back(q);
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
  r.median_error_mm = 1000.0 * percentile(e, 0.5);
  r.p99_error_mm = 1000.0 * percentile(e, 0.99);
  r.max_error_mm = e.empty() ? 0.0 : 1000.0 * e.back();
  r.yaw_p99_deg = kDegPerRad * percentile(y, 0.99);
  r.yaw_max_deg = y.empty() ? 0.0 : kDegPerRad * y.back();
  std::vector<double> q = nees_;
  std::sort(q.begin(), q.end());
  double sum = 0.0;
  for (double v : q) sum += v;
  r.mean_nees = q.empty() ? 0.0 : sum / static_cast<double>(q.size());
  r.median_nees = percentile(q, 0.5);
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
