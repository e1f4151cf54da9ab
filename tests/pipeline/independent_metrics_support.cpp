#include "independent_metrics_support.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace ceilpose::testing::xcheck {

int frames_for(int release_frames) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  return std::max(6, release_frames / 6);
#else
  return release_frames;
#endif
}

double wrapped_rad(double a_rad) { return std::remainder(a_rad, 2.0 * std::numbers::pi); }

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t k = static_cast<size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1;
  return v[std::min(k, v.size() - 1)];
}

void Spec6Figures::add(const XPose& truth, bool whole_marker_in_view,
                       const std::optional<XPose>& reported) {
  ++frames;
  with_whole += whole_marker_in_view;
  if (!reported) return;
  ++valid;
  valid_with_whole += whole_marker_in_view;
  const double dx_m = reported->x_m - truth.x_m, dy_m = reported->y_m - truth.y_m;
  const double dyaw_deg =
      std::abs(wrapped_rad(reported->yaw_rad - truth.yaw_rad)) * 180.0 / std::numbers::pi;
  const double err_m = std::hypot(dx_m, dy_m);
  yaw_out_of_range +=
      !(reported->yaw_rad > -std::numbers::pi && reported->yaw_rad <= std::numbers::pi);
  within_both += std::abs(dx_m) <= 0.05 * kGridUnit_m && std::abs(dy_m) <= 0.05 * kGridUnit_m;
  gross += err_m > 0.25 * kGridUnit_m || dyaw_deg > 5.0;
  error_mm.push_back(err_m * 1000.0);
  yaw_error_deg.push_back(dyaw_deg);
  const double c = std::cos(truth.yaw_rad), s = std::sin(truth.yaw_rad);
  sum_forward_mm += (c * dx_m + s * dy_m) * 1000.0;
  sum_left_mm += (-s * dx_m + c * dy_m) * 1000.0;
}

double Spec6Figures::availability() const {
  return with_whole ? static_cast<double>(valid_with_whole) / with_whole : 1.0;
}
double Spec6Figures::both_share() const {
  return valid ? static_cast<double>(within_both) / valid : 0.0;
}
double Spec6Figures::bias_forward_mm() const { return valid ? sum_forward_mm / valid : 0.0; }
double Spec6Figures::bias_left_mm() const { return valid ? sum_left_mm / valid : 0.0; }

void Spec6Figures::print(const char* tag, const std::string& name) const {
  std::printf(
      "[%s] %-14s frames %3d  whole %3d  valid %3d  avail %.3f  both-axes %.3f  median %.2f mm  "
      "p99 %.2f mm  max %.2f mm  yaw p99 %.3f deg  max %.3f deg  gross %d  decoded %d  wrong %d  "
      "bias fwd %+.2f left %+.2f mm\n",
      tag, name.c_str(), frames, with_whole, valid, availability(), both_share(), median_mm(),
      p99_mm(), max_mm(), yaw_p99_deg(), yaw_max_deg(), gross, decoded, wrong_codes,
      bias_forward_mm(), bias_left_mm());
}

}  // namespace ceilpose::testing::xcheck
