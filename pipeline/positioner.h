#pragma once
// Positioning: from the decoded markers of one frame to the robot's pose, by
// the mode asked for (or the best one the view allows, in auto).
#include <array>
#include <span>

#include "pipeline/change_of_axes.h"
#include "pipeline/lsq_solver.h"
#include "pipeline/marker_observation.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/pose_estimate.h"

namespace ceilpose {

// The reconcile step's account of one frame: how many decoded markers were
// believed, and why each other one was not. lsq's residual rejections are
// counted by the positioning that follows it.
struct ReconcileCounts {
  int believed = 0;      // passed to positioning
  int cut_off = 0;       // not wholly in view: a cut-off marker's code may be misread
  int unmapped = 0;      // not on the map (or its red and green centres coincide)
  int lone_unclear = 0;  // the only marker, its dots too faint to trust without another
  int inconsistent = 0;  // disagrees with the majority on where the camera is
  int residual = 0;      // lsq rejected it: its points do not fit the pose
  int rejected() const { return cut_off + unmapped + lone_unclear + inconsistent + residual; }
};

// Not thread-safe: one instance per pipeline thread. solve() allocates
// nothing and throws nothing.
class Positioner {
 public:
  explicit Positioner(const PipelineConfig& config);

  // Uses whole markers only (a cut-off marker's code may be misread). The
  // estimate is invalid when no whole marker is seen, the markers disagree
  // with no majority, or the mode asked for cannot be applied to this view
  // (e.g. barycentric with fewer than three markers) — never a made-up pose.
  // `motion` (rolling shutter): the camera's motion during the readout when
  // known from elsewhere; each marker's answer is moved to the centre row by
  // it, and lsq holds it when the rows cannot tell the motion.
  PoseEstimate solve(std::span<const MarkerObservation> markers, PositioningMode mode,
                     const CameraMotion& motion = {});

  // solve() in its two steps, which the pipeline times apart. reconcile()
  // decides which decoded markers to believe (whole, mapped, clear enough
  // alone, grid-consistent, at the configured heights); kNone when some are,
  // else the refusal. position() then solves the mode from the believed ones.
  Refusal reconcile(std::span<const MarkerObservation> markers, const CameraMotion& motion);
  PoseEstimate position(std::span<const MarkerObservation> markers, PositioningMode mode,
                        const CameraMotion& motion);
  // The last frame's reconcile, with position()'s residual rejections.
  const ReconcileCounts& reconcile_counts() const { return counts_; }

  // Details of the last least-squares solve (tilt, iterations), for
  // diagnostics and tests.
  const LsqResult& last_lsq() const { return lsq_result_; }

 private:
  PoseEstimate change_of_axes(int fix_count);
  PoseEstimate barycentric(int fix_count);
  PoseEstimate least_squares(std::span<const MarkerObservation> markers, int fix_count,
                             const CameraMotion& motion);
  void set_thesis_covariance(PoseEstimate* estimate, int fix_count) const;
  double depth_scale(int fix_count);
  PoseEstimate solve_mode(std::span<const MarkerObservation> markers, int fix_count,
                          PositioningMode mode, const CameraMotion& motion);
  void time_the_pose(std::span<const MarkerObservation> markers, int fix_count,
                     const CameraMotion& motion, PoseEstimate* est) const;

  PositioningParams params_;
  ReconcileCounts counts_;
  int fix_count_ = 0;
  int inliers_ = 0;
  double depth_scale_ = 0.0;
  Refusal refusal_ = Refusal::kNone;
  ViewGeometry view_;
  LsqSolver lsq_;
  LsqResult lsq_result_;
  std::array<MarkerFix, kMaxMarkersPerFrame> fixes_{};
  std::array<bool, kMaxMarkersPerFrame> inlier_{};
  std::array<bool, kMaxMarkersPerFrame> use_{};  // lsq's, then the mode's markers
  std::array<double, kMaxMarkersPerFrame*(kMaxMarkersPerFrame - 1) / 2> pair_scales_{};
};

}  // namespace ceilpose
