#pragma once
// Least squares over everything seen: the camera's full attitude (position,
// yaw, roll/pitch tilt, optionally height) from every point of every
// consistent marker, by Levenberg–Marquardt on the reprojection error with
// Huber weights, marker-level outlier rejection, and a covariance of the
// robot's (x, y, yaw) (lsq_covariance.h). The solve reads as named steps
// (lsq_solver.cpp): gather the points, choose the tilt model, accept,
// covariance. Its terms (residuals, Jacobians, priors) are lsq_terms.h's.
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "core/pose.h"
#include "pipeline/change_of_axes.h"
#include "pipeline/lsq_covariance.h"
#include "pipeline/lsq_terms.h"
#include "pipeline/marker_observation.h"
#include "pipeline/positioning_params.h"

namespace ceilpose {

// How the tilt model was chosen, and on what evidence.
enum class TiltChoice : uint8_t {
  kNotAllowed,  // estimation off, or fewer than lsq_tilt_min_markers markers
  kHeldFits,    // the free fit neither fits significantly better nor moves the pose
  kFreeFailed,  // the free fit diverged, lost markers, or found a tilt no mount has
  kFreeFits,    // estimated: significantly better, and it moves the pose
};
const char* to_string(TiltChoice choice);

struct LsqResult {
  Pose2D robot;
  std::array<double, 9> covariance{};  // (x_m, y_m, yaw_rad), row-major
  double rms_px = 0.0;                 // inliers' RMS reprojection residual
  int markers = 0;                     // markers kept after rejection
  int rejected = 0;                    // markers rejected for their residual
  int points = 0;
  int iterations = 0;
  double tilt_x_rad = 0.0;  // estimated camera tilt (core's tilt convention)
  double tilt_y_rad = 0.0;
  double lens_height_m = 0.0;
  bool tilt_estimated = false;  // false: held at the mount's nominal tilt
  TiltChoice tilt_choice = TiltChoice::kNotAllowed;
  // The tilt decision's evidence: how far the free-tilt pose is from the
  // held-tilt one, metres, and by how much freeing the tilt lowered the
  // cost, in units of the free fit's noise (chi-square).
  double tilt_shift_m = 0.0;
  double tilt_free_sigma_m = 0.0;  // the free-tilt pose's own 1-sigma, metres (0: not needed)
  double tilt_chi2 = 0.0;
  // Rolling shutter (camera.readout_ms > 0): the optical centre's velocity
  // and the yaw rate during the readout, world frame, when the markers span
  // enough rows to tell them (motion_estimated); the pose is the centre row's.
  double cam_vx_mps = 0.0;
  double cam_vy_mps = 0.0;
  double yaw_rate_radps = 0.0;
  bool motion_estimated = false;
  bool motion_held = false;  // not estimated: held at the caller's motion
  // The edge points' outward offset, pixels (lsq_terms.h); 0 without them.
  double edge_offset_px = 0.0;
};

// Holds the per-frame work arrays (sized for the largest frame), so solve()
// never allocates. One instance per thread.
class LsqSolver {
 public:
  LsqSolver();

  // `use` flags the markers (indices into fixes) to solve from; markers
  // rejected as outliers are cleared in it. Seeds from the fixes' Change of
  // Axes answers. `motion` (when valid, rolling shutter only) is the prior of
  // the motion during the readout, and its value when the rows cannot tell
  // it. False when too few points, no convergence or the residual stays
  // above params.lsq_max_rms_px.
  bool solve(const ViewGeometry& view, const PositioningParams& params,
             std::span<const MarkerObservation> markers, std::span<const MarkerFix> fixes,
             std::span<bool> use, const CameraMotion& motion, LsqResult* out);

 private:
  // One fit of one model: its markers, state and cost.
  struct Fit {
    LsqModel model;
    LsqState state;
    std::array<bool, kMaxMarkersPerFrame> use{};
    int markers = 0;
    double cost = INFINITY;  // not finite: no solution
    // What optimise ended with: the normal matrix (priors included) at
    // `state` over the markers in `use`, and the Huber-weighted squared
    // residuals over their count. Valid while cost is finite and the fit is
    // not changed after optimise.
    LsqNormal a{};
    LsqVector b{};
    double wr2 = 0.0;
    int residuals = 0;
    // Asked for (want_) and held (tilt_columns): a and b hold the tilt's rows
    // as well, for the tilt decision that follows a held fit
    // (free_tilt_gain_chi2), which then needs no pass of its own over the
    // points. The model's solve ignores them. Only the trials' passes
    // gather them: a fit's first pass is almost never its last.
    bool want_tilt_columns = false;
    bool tilt_columns = false;
    // Which of terms_ holds the points' PointTerms at `state` from the pass
    // that gave `a` (-1: none kept).
    int terms_slot = -1;
  };
  std::span<PointTerms> terms(int slot) {
    return slot < 0 ? std::span<PointTerms>{} : std::span(terms_[static_cast<size_t>(slot)]);
  }

  // The steps of solve(), in order (see lsq_solver.cpp).
  int gather_points(const ViewGeometry& view, const PositioningParams& params,
                    std::span<const MarkerObservation> markers, std::span<const MarkerFix> fixes,
                    std::span<const bool> use, const LsqModel& model, LsqState* seed);
  Fit choose_tilt_model(const ViewGeometry& view, const PositioningParams& params,
                        std::span<const MarkerFix> fixes, const Fit& seed, int* iterations,
                        LsqResult* out);
  void optimise(const ViewGeometry& view, const PositioningParams& params,
                std::span<const MarkerFix> fixes, Fit* fit, int* iterations);
  int worst_marker(const ViewGeometry& view, const PositioningParams& params,
                   std::span<const MarkerFix> fixes, const Fit& fit) const;
  bool motion_observable(const ViewGeometry& view, const PositioningParams& params,
                         std::span<const bool> use, int marker_count) const;
  bool edge_points_in_use(std::span<const bool> use) const;
  bool reweigh_edges(const ViewGeometry& view, Fit* fit) const;
  double free_tilt_gain_chi2(const ViewGeometry& view, const PositioningParams& params,
                             const Fit& held) const;
  double position_sigma_m(const LsqModel& model, const LsqNormal& a, double wr2, int n) const;
  double rms_px(const ViewGeometry& view, std::span<const bool> use, const LsqState& st,
                int n) const;
  std::span<const LsqPoint> points() const { return {points_.data(), size_t(point_count_)}; }

  std::array<LsqPoint, kMaxMarkersPerFrame * kMaxPointsPerMarker> points_{};
  int point_count_ = 0;
  int edge_points_ = 0;  // of point_count_
  LsqCovariance covariance_;
  // PointTerms for the covariance, one per point of points_, in three slots:
  // the held fit's, the free fit's and a trial's, whose slot a fit takes
  // with the trial (sized once: a solve allocates nothing).
  std::array<std::vector<PointTerms>, 3> terms_;
  int trial_slot_ = 2;
};

}  // namespace ceilpose
