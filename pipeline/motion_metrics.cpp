#include "pipeline/motion_metrics.h"

#include <algorithm>
#include <cmath>

#include "core/units.h"
#include "pipeline/accuracy_metrics.h"

namespace ceilpose {
namespace {

double sorted_percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return percentile(v, p);
}

}  // namespace

void MotionAccuracySink::consume(const Localization& loc) {
  if (!loc.frame.has_ground_truth) return;
  truth_.push_back({loc.frame.timestamp_ns, loc.frame.ground_truth});
  if (!loc.published.valid || !loc.motion.valid) return;
  if (static_cast<int>(truth_.size()) <= settle_frames_) return;
  const MotionState& s = loc.motion.state;
  const int64_t ahead_ns = loc.frame.timestamp_ns + std::llround(predict_ms_ * 1e6);
  const MotionState ahead = motion_at(loc.motion, ahead_ns);
  samples_.push_back({truth_.size() - 1, loc.published.pose, s.x[3], s.x[4], s.x[5],
                      Pose2D{ahead.x[0], ahead.x[1], ahead.x[2]}});
}

MotionReport MotionAccuracySink::report() const {
  MotionReport r;
  r.predict_ms = predict_ms_;
  std::vector<double> err, yaw, verr, wrate, perr, pyaw, uerr;
  const int64_t ahead_ns = std::llround(predict_ms_ * 1e6);
  for (const Sample& s : samples_) {
    const Truth& t = truth_[s.truth];
    err.push_back(std::hypot(s.pose.x_m - t.pose.x_m, s.pose.y_m - t.pose.y_m));
    yaw.push_back(std::abs(wrap_angle_rad(s.pose.yaw_rad - t.pose.yaw_rad)));
    if (s.truth > 0 && s.truth + 1 < truth_.size()) {
      const Truth& a = truth_[s.truth - 1];
      const Truth& b = truth_[s.truth + 1];
      const double dt_s = static_cast<double>(b.t_ns - a.t_ns) * 1e-9;
      if (dt_s > 0.0) {
        const double vx = (b.pose.x_m - a.pose.x_m) / dt_s, vy = (b.pose.y_m - a.pose.y_m) / dt_s;
        const double w = wrap_angle_rad(b.pose.yaw_rad - a.pose.yaw_rad) / dt_s;
        verr.push_back(std::hypot(s.vx_mps - vx, s.vy_mps - vy));
        wrate.push_back(std::abs(s.yaw_rate_radps - w));
      }
    }
    // The truth at t + ahead: between the recorded truths around it.
    const int64_t want_ns = t.t_ns + ahead_ns;
    auto it = std::lower_bound(truth_.begin() + static_cast<std::ptrdiff_t>(s.truth), truth_.end(),
                               want_ns, [](const Truth& x, int64_t v) { return x.t_ns < v; });
    if (it == truth_.end()) continue;
    Pose2D at = it->pose;
    if (it->t_ns != want_ns && it != truth_.begin()) {
      const Truth& lo = *(it - 1);
      const double f =
          static_cast<double>(want_ns - lo.t_ns) / static_cast<double>(it->t_ns - lo.t_ns);
      at = {
          lo.pose.x_m + f * (it->pose.x_m - lo.pose.x_m),
          lo.pose.y_m + f * (it->pose.y_m - lo.pose.y_m),
          wrap_angle_rad(lo.pose.yaw_rad + f * wrap_angle_rad(it->pose.yaw_rad - lo.pose.yaw_rad))};
    }
    perr.push_back(std::hypot(s.predicted.x_m - at.x_m, s.predicted.y_m - at.y_m));
    pyaw.push_back(std::abs(wrap_angle_rad(s.predicted.yaw_rad - at.yaw_rad)));
    uerr.push_back(std::hypot(s.pose.x_m - at.x_m, s.pose.y_m - at.y_m));
  }
  r.frames = static_cast<int>(err.size());
  r.median_error_mm = 1000.0 * sorted_percentile(err, 0.5);
  r.p99_error_mm = 1000.0 * sorted_percentile(err, 0.99);
  r.max_error_mm = 1000.0 * sorted_percentile(err, 1.0);
  r.yaw_p99_deg = kDegPerRad * sorted_percentile(yaw, 0.99);
  r.velocity_frames = static_cast<int>(verr.size());
  r.velocity_median_error_mps = sorted_percentile(verr, 0.5);
  r.velocity_p99_error_mps = sorted_percentile(verr, 0.99);
  r.yaw_rate_median_error_radps = sorted_percentile(wrate, 0.5);
  r.predicted_frames = static_cast<int>(perr.size());
  r.predicted_median_error_mm = 1000.0 * sorted_percentile(perr, 0.5);
  r.predicted_p99_error_mm = 1000.0 * sorted_percentile(perr, 0.99);
  r.predicted_max_error_mm = 1000.0 * sorted_percentile(perr, 1.0);
  r.predicted_yaw_p99_deg = kDegPerRad * sorted_percentile(pyaw, 0.99);
  r.unpredicted_p99_error_mm = 1000.0 * sorted_percentile(uerr, 0.99);
  return r;
}

}  // namespace ceilpose
