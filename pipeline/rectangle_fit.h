#pragma once
// Stage 2: rectangle template fit. Keeps the red and green components whose
// area, aspect ratio and fill match a marker rectangle (5 × 12 in, SPEC §2)
// as the camera model predicts it, and describes each by its centre, axes
// and side lengths from the second moments.
#include <span>

#include "core/camera_model.h"
#include "core/ceiling_layout.h"
#include "pipeline/components.h"
#include "pipeline/detector_params.h"

namespace ceilpose {

struct RectangleCandidate {
  PixelClass cls = PixelClass::kBackground;
  int component = -1;         // index into the component list
  double cx = 0.0, cy = 0.0;  // centroid, pixels
  double axis_rad = 0.0;      // long-axis direction in the image, (−π/2, π/2]
  double long_px = 0.0;       // side lengths of the rectangle with the same moments
  double short_px = 0.0;
  double area_px = 0.0;
  double dark_px = 0.0;
  double fill = 0.0;  // area / (long × short)
  bool touches_border = false;
};

// Size of a marker rectangle in the image, from the camera model.
struct RectangleModel {
  double px_per_m = 0.0;  // image scale on the ceiling plane
  double expected_area_px = 0.0;
  double expected_long_px = 0.0;
  double expected_short_px = 0.0;
  // With lens distortion, shape tests run on the blob's moments mapped back
  // to the undistorted image, and centroids are corrected for the shift
  // that distortion's curvature gives an area centroid.
  CameraIntrinsics intrinsics;
  bool distorted = false;
};

// Scale at the image centre for a level camera: f / (H − h).
RectangleModel make_rectangle_model(const CameraIntrinsics& intrinsics, const CameraMount& mount,
                                    const CeilingLayout& layout);

// Fits every red and green component; writes the accepted ones to `out` and
// returns how many (at most out.size()). Hot path: no allocation.
int fit_rectangles(std::span<const Component> components, const RectangleModel& model,
                   const DetectorParams& params, std::span<RectangleCandidate> out);

}  // namespace ceilpose
