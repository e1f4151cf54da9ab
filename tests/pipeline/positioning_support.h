#pragma once
// Exact synthetic marker observations for the positioning tests: the
// marker-frame points of SPEC §2 projected with core/camera_model.h for a
// known robot pose, optionally with Gaussian pixel noise.
#include <cstdint>
#include <vector>

#include "core/camera_model.h"
#include "core/ceiling_layout.h"
#include "pipeline/change_of_axes.h"
#include "pipeline/marker_observation.h"

namespace ceilpose::testing {

struct SyntheticView {
  CameraIntrinsics intrinsics;
  CameraMount mount;  // the true mount (may differ from the configured one)
  CeilingLayout layout;
  double noise_px = 0.0;
  uint64_t seed = 1;
  bool include_partial = false;  // also emit markers cut by the image border
  // Rolling shutter (intrinsics.readout_ms > 0): the robot's velocity, m/s
  // in its own frame (forward, left), and its yaw rate, held constant (a
  // constant twist, integrated exactly): each point is projected from the
  // robot's pose when its own row was exposed.
  double forward_mps = 0.0, left_mps = 0.0, yaw_rate_radps = 0.0;
};

// The robot `tau_s` after `robot` under `view`'s constant twist, exactly.
Pose2D pose_after(const SyntheticView& view, const Pose2D& robot, double tau_s);

// All markers of the layout's grid whose outline is inside the image.
std::vector<MarkerObservation> observe(const SyntheticView& view, const Pose2D& robot);

// Change of Axes answers of those markers that give one.
std::vector<MarkerFix> fixes_of(const ViewGeometry& view,
                                const std::vector<MarkerObservation>& markers);

}  // namespace ceilpose::testing
