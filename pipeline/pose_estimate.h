#pragma once
#include <array>
#include <cstdint>

#include "core/pose.h"
#include "core/positioning_mode.h"
#include "core/refusal.h"

namespace ceilpose {

struct PoseEstimate {
  bool valid = false;
  Pose2D pose;                         // robot pose in `map`
  std::array<double, 9> covariance{};  // (x_m, y_m, yaw_rad), row-major, SI units squared
  PositioningMode mode = PositioningMode::kAuto;  // method actually used
  int markers = 0;                                // decoded markers used
  double rms_residual_px = 0.0;                   // reprojection residual of the solution
  // Camera-to-ceiling distance the markers' spacing implies, as a fraction of
  // the configured one (median over pairs of consistent markers); 0 when
  // fewer than two markers. Set on refused estimates too, so that callers can
  // say why a view full of markers gives no pose.
  double depth_scale = 0.0;
  // Rolling shutter: when the rows the pose was measured from were exposed,
  // seconds after the frame's time (the centre row). 0 for a global shutter
  // and when the solve modelled the motion within the frame. The temporal
  // filter fuses the pose at that instant.
  double time_offset_s = 0.0;
  // Why there is no pose (kNone when valid): set by the stage that refused.
  Refusal refusal = Refusal::kNone;
};

// An invalid estimate that says why.
inline PoseEstimate refused_estimate(Refusal why, double depth_scale = 0.0) {
  PoseEstimate e;
  e.refusal = why;
  e.depth_scale = depth_scale;
  return e;
}

}  // namespace ceilpose
