#pragma once
// Helpers the simulator tests share: pixel access, colour unmixing and the
// dense projection of outlines that rendered blobs are compared with.
#include <array>
#include <vector>

#include "core/camera_model.h"
#include "core/ceiling_layout.h"
#include "core/image.h"
#include "sim/effects.h"

namespace ceilpose::sim::testing {

// Every effect switched on at a moderate level; `jpeg_quality` 0 leaves the
// JPEG round trip out.
Effects every_effect(int jpeg_quality);

struct Point2 {
  double u = 0.0, v = 0.0;
};

inline std::array<uint8_t, 3> pixel(const Image& img, int u, int v) {
  const uint8_t* p = img.data() + static_cast<size_t>(v) * img.stride_bytes() + u * 3;
  return {p[0], p[1], p[2]};
}

// Area centroid of the image of a world polygon on the ceiling, from its
// outline projected densely (distortion bends straight edges).
Point2 projected_polygon_centroid(const CameraIntrinsics& k, const CameraPose& camera,
                                  const std::vector<Vec3>& corners_w);

// Coverage-weighted centroid of the pixels in window [u0,u1]x[v0,v1] whose
// colour unmixes (in linear light, against tile, red, green and dot) into
// the given selection of marker materials.
struct Unmixed {
  double red = 0.0, green = 0.0, dot = 0.0;
};
Unmixed unmix(const CeilingLayout& layout, const std::array<uint8_t, 3>& srgb);

enum class Part { kRed, kGreen, kWholeMarker };
Point2 coverage_centroid(const CeilingLayout& layout, const Image& img, int u0, int v0, int u1,
                         int v1, Part part, double* coverage_px = nullptr);

}  // namespace ceilpose::sim::testing
