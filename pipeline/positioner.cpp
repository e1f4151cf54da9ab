#include "pipeline/positioner.h"

#include <algorithm>
#include <cmath>

#include "core/length_2d.h"
#include "pipeline/barycentric.h"
#include "pipeline/camera_motion.h"
#include "pipeline/grid_consistency.h"

namespace ceilpose {
namespace {

// A lone marker has no other to check its code against, and a misread one
// puts the pose whole grid units off. Its dots must read clearly: quality
// 0.5 is a slot margin of 0.15 from the dot threshold with a good pairing.
// On the simulator at 320×240 every wrong code that reached a pose (before
// the threshold followed blur) had a margin of 0.10–0.15.
constexpr float kLoneMarkerMinQuality = 0.5f;

}  // namespace

Positioner::Positioner(const PipelineConfig& config) : params_(config.positioning), view_(config) {}

// The thesis modes have no residuals; their measured accuracy plus the
// least certain mapped place among the markers they may have used.
void Positioner::set_thesis_covariance(PoseEstimate* estimate, int fix_count) const {
  double map_var_m2 = 0.0, map_var_rad2 = 0.0;
  for (int k = 0; k < fix_count; ++k) {
    if (!inlier_[k]) continue;
    const MarkerPlacement& p = *fixes_[k].placement;
    map_var_m2 = std::max(map_var_m2, p.sigma_m * p.sigma_m);
    map_var_rad2 = std::max(map_var_rad2, p.sigma_yaw_rad * p.sigma_yaw_rad);
  }
  estimate->covariance.fill(0.0);
  estimate->covariance[0] = estimate->covariance[4] =
      params_.thesis_sigma_m * params_.thesis_sigma_m + map_var_m2;
  estimate->covariance[8] =
      params_.thesis_sigma_yaw_rad * params_.thesis_sigma_yaw_rad + map_var_rad2;
}

// For a level camera, markers d_w apart on the ceiling appear d_w / depth
// apart in normalized image coordinates, whatever the pose; tilt and the
// residual distortion bend that by a few percent at most, so the median over
// all pairs measures the depth the configuration should have said.
double Positioner::depth_scale(int fix_count) {
  size_t pairs = 0;
  for (int a = 0; a < fix_count; ++a) {
    if (!inlier_[a]) continue;
    for (int b = a + 1; b < fix_count; ++b) {
      if (!inlier_[b]) continue;
      const double world_m = length_2d(fixes_[a].world_x_m - fixes_[b].world_x_m,
                                       fixes_[a].world_y_m - fixes_[b].world_y_m);
      const double image_n = length_2d(fixes_[a].centre_x_n - fixes_[b].centre_x_n,
                                       fixes_[a].centre_y_n - fixes_[b].centre_y_n);
      if (world_m <= 0.0 || image_n <= 0.0) continue;
      pair_scales_[pairs++] = world_m / image_n / view_.depth_m();
    }
  }
  if (pairs == 0) return 0.0;
  const auto mid = pair_scales_.begin() + static_cast<ptrdiff_t>(pairs / 2);
  std::nth_element(pair_scales_.begin(), mid, pair_scales_.begin() + static_cast<ptrdiff_t>(pairs));
  return *mid;
}

// Thesis Change of Axes uses one marker: the consistent one nearest the
// image centre, where tilt and distortion errors are smallest.
PoseEstimate Positioner::change_of_axes(int fix_count) {
  PoseEstimate est;
  int best = -1;
  double best_r2 = 0.0;
  for (int k = 0; k < fix_count; ++k) {
    if (!inlier_[k]) continue;
    const double r2 =
        fixes_[k].centre_x_n * fixes_[k].centre_x_n + fixes_[k].centre_y_n * fixes_[k].centre_y_n;
    if (best < 0 || r2 < best_r2) {
      best = k;
      best_r2 = r2;
    }
  }
  if (best < 0) return est;
  use_.fill(false);
  use_[best] = true;
  const MarkerFix& f = fixes_[best];
  est.pose = view_.robot_from_camera(f.cam_x_m, f.cam_y_m, f.cam_yaw_rad);
  est.valid = true;
  est.mode = PositioningMode::kChangeOfAxes;
  est.markers = 1;
  set_thesis_covariance(&est, fix_count);
  return est;
}

PoseEstimate Positioner::barycentric(int fix_count) {
  PoseEstimate est;
  std::array<int, 3> chosen{};
  if (!solve_barycentric(view_, params_, std::span(fixes_.data(), fix_count),
                         std::span(inlier_.data(), fix_count), &est.pose, &chosen)) {
    return est;
  }
  use_.fill(false);
  for (int k : chosen) use_[k] = true;
  est.valid = true;
  est.mode = PositioningMode::kBarycentric;
  est.markers = 3;
  set_thesis_covariance(&est, fix_count);
  return est;
}

PoseEstimate Positioner::least_squares(std::span<const MarkerObservation> markers, int fix_count,
                                       const CameraMotion& motion) {
  PoseEstimate est;
  for (int k = 0; k < fix_count; ++k) use_[k] = inlier_[k];
  lsq_result_ = LsqResult{};
  if (!lsq_.solve(view_, params_, markers, std::span(fixes_.data(), fix_count),
                  std::span(use_.data(), fix_count), motion, &lsq_result_)) {
    return est;
  }
  est.valid = true;
  est.pose = lsq_result_.robot;
  est.covariance = lsq_result_.covariance;
  est.mode = PositioningMode::kLeastSquares;
  est.markers = lsq_result_.markers;
  est.rms_residual_px = lsq_result_.rms_px;
  return est;
}

PoseEstimate Positioner::solve(std::span<const MarkerObservation> markers, PositioningMode mode,
                               const CameraMotion& motion) {
  reconcile(markers, motion);
  return position(markers, mode, motion);
}

// The reconcile step: which decoded markers to believe, and why each other
// one is not, in a fixed order (whole, mapped, clear enough alone, agreeing
// with the majority); then whether the believed ones agree with the
// configured heights.
Refusal Positioner::reconcile(std::span<const MarkerObservation> markers,
                              const CameraMotion& motion) {
  counts_ = ReconcileCounts{};
  fix_count_ = inliers_ = 0;
  depth_scale_ = 0.0;
  // 1. What each whole marker says on its own (Change of Axes), at the
  // centre row's instant when the motion during the readout is known.
  int whole = 0;
  const int n = static_cast<int>(std::min<size_t>(markers.size(), kMaxMarkersPerFrame));
  for (int k = 0; k < n; ++k) {
    if (!markers[k].whole) {
      ++counts_.cut_off;
      continue;
    }
    ++whole;
    if (marker_fix(view_, markers[k], k, motion, &fixes_[fix_count_]))
      ++fix_count_;
    else
      ++counts_.unmapped;
  }
  if (fix_count_ == 0)
    return refusal_ = whole > 0 && view_.map().surveyed() ? Refusal::kUnmappedMarkers
                                                          : Refusal::kNoWholeMarker;
  if (fix_count_ == 1 && markers[fixes_[0].index].quality < kLoneMarkerMinQuality) {
    counts_.lone_unclear = 1;
    return refusal_ = Refusal::kLoneMarkerUnclear;
  }
  // 2. Keep the markers that agree on where the camera is.
  inliers_ =
      grid_consistent_subset(params_, view_.layout().grid_m, std::span(fixes_.data(), fix_count_),
                             std::span(inlier_.data(), fix_count_));
  counts_.inconsistent = fix_count_ - inliers_;
  if (inliers_ == 0) return refusal_ = Refusal::kInconsistentMarkers;
  counts_.believed = inliers_;
  // 3. The configured heights must match what the markers' spacing says.
  depth_scale_ = depth_scale(fix_count_);
  if (depth_scale_contradicts_heights(params_, depth_scale_))
    return refusal_ = Refusal::kWrongHeights;
  return refusal_ = Refusal::kNone;
}

PoseEstimate Positioner::position(std::span<const MarkerObservation> markers, PositioningMode mode,
                                  const CameraMotion& motion) {
  if (refusal_ != Refusal::kNone) return refused_estimate(refusal_, depth_scale_);
  // 4. The mode asked for, or in auto the best the view allows.
  PoseEstimate est = solve_mode(markers, fix_count_, mode, motion);
  est.depth_scale = depth_scale_;
  if (est.valid && est.mode == PositioningMode::kLeastSquares) {
    counts_.residual = lsq_result_.rejected;
    counts_.believed -= lsq_result_.rejected;
  }
  if (est.valid) time_the_pose(markers, fix_count_, motion, &est);
  if (!est.valid) {
    // A solver given fewer markers than it needs did not fail: the view did.
    int inlier_points = 0;
    for (int k = 0; k < fix_count_; ++k)
      if (inlier_[k]) inlier_points += markers[fixes_[k].index].point_count;
    const bool too_few =
        (mode == PositioningMode::kBarycentric && inliers_ < 3) ||
        (mode == PositioningMode::kLeastSquares && inlier_points < params_.lsq_min_points);
    est.refusal = too_few ? Refusal::kTooFewMarkers : Refusal::kSolverRejected;
  }
  return est;
}

PoseEstimate Positioner::solve_mode(std::span<const MarkerObservation> markers, int fix_count,
                                    PositioningMode mode, const CameraMotion& motion) {
  switch (mode) {
    case PositioningMode::kChangeOfAxes:
      return change_of_axes(fix_count);
    case PositioningMode::kBarycentric:
      return barycentric(fix_count);
    case PositioningMode::kLeastSquares:
      return least_squares(markers, fix_count, motion);
    case PositioningMode::kAuto:
      break;
  }
  PoseEstimate est = least_squares(markers, fix_count, motion);
  if (est.valid) return est;
  est = barycentric(fix_count);
  if (est.valid) return est;
  return change_of_axes(fix_count);
}

// Rolling shutter, the motion within the frame not estimated from it: a pose
// from the markers' rows is the pose of when those rows were exposed. Told
// the camera's motion, the markers were compared and combined at the centre
// row; the pose is carried back to their rows' instant, so that it does not
// depend on the motion it was told: fed back through the filter, a told
// yaw rate that moved a lone marker's heading would raise itself.
void Positioner::time_the_pose(std::span<const MarkerObservation> markers, int fix_count,
                               const CameraMotion& motion, PoseEstimate* est) const {
  const CameraIntrinsics& k = view_.intrinsics();
  if (!(k.readout_ms > 0.0)) return;
  if (est->mode == PositioningMode::kLeastSquares && lsq_result_.motion_estimated) return;
  double tau_sum_s = 0.0;
  int used = 0;
  for (int f = 0; f < fix_count; ++f) {
    if (!use_[f]) continue;
    tau_sum_s += row_time_s(k, markers[fixes_[f].index].centre_v_px);
    ++used;
  }
  if (used == 0) return;
  const double tau_s = tau_sum_s / used;
  est->time_offset_s = tau_s;
  if (!motion.valid) return;
  const double yaw = est->pose.yaw_rad;
  const CameraMount& m = view_.mount();
  double ox_m = 0.0, oy_m = 0.0;
  mount_offset_world(m, yaw, &ox_m, &oy_m);
  const double cam_x_m = est->pose.x_m + ox_m, cam_y_m = est->pose.y_m + oy_m;
  double arc_x_m = 0.0, arc_y_m = 0.0;
  arc_displacement(motion.vx_mps, motion.vy_mps, motion.yaw_rate_radps, tau_s, &arc_x_m, &arc_y_m);
  est->pose = view_.robot_from_camera(cam_x_m + arc_x_m, cam_y_m + arc_y_m,
                                      yaw + m.yaw_rad + motion.yaw_rate_radps * tau_s);
}

}  // namespace ceilpose
