#pragma once
// Crafted test images for the detection stages: markers drawn directly in
// image space (an affine view, no camera model), anti-aliased by 8 × 8
// supersampling in linear light, with an optional exposure gain and colour
// cast; conversions to the other pixel formats the pipeline accepts.
#include <array>
#include <span>

#include "core/camera_model.h"
#include "core/ceiling_layout.h"
#include "core/image.h"
#include "sim/camera_format.h"

namespace ceilpose::test {

struct CraftedMarker {
  double centre_u_px = 320.0;
  double centre_v_px = 240.0;
  double west_image_rad = 0.5 * 3.14159265358979323846;  // West = image down (yaw 0)
  int code_i = 0;
  int code_j = 0;
};

struct Lighting {
  double gain = 1.0;                          // multiplies linear light
  std::array<double, 3> cast{1.0, 1.0, 1.0};  // per-channel R, G, B
};

// Image scale of the SPEC ceiling seen by the default camera: 530 / 2.1336 m.
inline constexpr double kDefaultPxPerM = 530.0 / (2.4384 - 0.3048);

// RGB24 frame of tile colour with the given markers.
Image render_markers(int width_px, int height_px, std::span<const CraftedMarker> markers,
                     const CeilingLayout& layout = {}, const Lighting& lighting = {},
                     double px_per_m = kDefaultPxPerM);

using sim::convert_rgb;

// RGB24 image box-blurred over `length_px` pixels along rows (North at
// yaw 0), edges clamped.
Image blur_rows(const Image& rgb, int length_px);

// The default camera at half resolution (320 × 240, same field of view).
CameraIntrinsics half_size_camera();
// The same at 1280x960 (fx = fy 1060): red dots of 13 px.
CameraIntrinsics double_size_camera();

// Pixel (x, y) of an RGB24 image set to (r, g, b).
void put_rgb(Image* image, int x, int y, Rgb colour);

}  // namespace ceilpose::test
