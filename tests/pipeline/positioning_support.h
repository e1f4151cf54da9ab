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
};

// All markers of the layout's grid whose outline is inside the image.
std::vector<MarkerObservation> observe(const SyntheticView& view, const Pose2D& robot);

// Change of Axes answers of those markers that give one.
std::vector<MarkerFix> fixes_of(const ViewGeometry& view,
                                const std::vector<MarkerObservation>& markers);

}  // namespace ceilpose::testing
