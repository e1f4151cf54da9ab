#include "tests/sim/sim_test_support.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

#include "sim/ceiling_scene.h"

namespace ceilpose::sim::testing {

Effects every_effect(int jpeg_quality) {
  Effects e;
  e.gain = 1.3;
  e.gradient_amplitude = 0.2;
  e.white_balance = {1.1, 0.95, 0.8};
  e.read_noise_sigma = 5.0;
  e.shot_noise_scale = 0.3;
  e.defocus_sigma_px = 1.0;
  e.motion_blur_px = 3.0;
  e.jpeg_quality = jpeg_quality;
  e.bloom = 0.5;
  e.occlusion_fraction = 0.1;
  e.clutter_objects = 8;
  return e;
}

Point2 projected_polygon_centroid(const CameraIntrinsics& k, const CameraPose& camera,
                                  const std::vector<Vec3>& corners_w) {
  constexpr int kPerEdge = 400;
  std::vector<Point2> outline;
  for (size_t e = 0; e < corners_w.size(); ++e) {
    const Vec3& a = corners_w[e];
    const Vec3& b = corners_w[(e + 1) % corners_w.size()];
    for (int s = 0; s < kPerEdge; ++s) {
      const double f = static_cast<double>(s) / kPerEdge;
      Point2 p;
      project_world_point(k, camera, {a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2]},
                          &p.u, &p.v);
      outline.push_back(p);
    }
  }
  // Shoelace formula.
  double area2 = 0.0, cu = 0.0, cv = 0.0;
  for (size_t i = 0; i < outline.size(); ++i) {
    const Point2& p = outline[i];
    const Point2& q = outline[(i + 1) % outline.size()];
    const double cross = p.u * q.v - q.u * p.v;
    area2 += cross;
    cu += (p.u + q.u) * cross;
    cv += (p.v + q.v) * cross;
  }
  return {cu / (3.0 * area2), cv / (3.0 * area2)};
}

Unmixed unmix(const CeilingLayout& layout, const std::array<uint8_t, 3>& srgb) {
  // pixel = tile + a_r (red - tile) + a_g (green - tile) + a_d (dot - tile),
  // in linear light, where area integration is linear.
  auto lin = [](Rgb c) {
    return cv::Vec3d(srgb_to_linear(c.r), srgb_to_linear(c.g), srgb_to_linear(c.b));
  };
  const cv::Vec3d tile = lin(layout.tile);
  const cv::Vec3d r = lin(layout.red) - tile, g = lin(layout.green) - tile,
                  d = lin(layout.dot) - tile;
  const cv::Matx33d m(r[0], g[0], d[0], r[1], g[1], d[1], r[2], g[2], d[2]);
  const cv::Vec3d p = lin(Rgb{srgb[0], srgb[1], srgb[2]}) - tile;
  const cv::Vec3d a = m.inv() * p;
  return {a[0], a[1], a[2]};
}

Point2 coverage_centroid(const CeilingLayout& layout, const Image& img, int u0, int v0, int u1,
                         int v1, Part part, double* coverage_px) {
  double sw = 0.0, su = 0.0, sv = 0.0;
  for (int v = std::max(0, v0); v <= std::min(img.height() - 1, v1); ++v)
    for (int u = std::max(0, u0); u <= std::min(img.width() - 1, u1); ++u) {
      const Unmixed a = unmix(layout, pixel(img, u, v));
      double w = part == Part::kRed     ? a.red
                 : part == Part::kGreen ? a.green
                                        : a.red + a.green + a.dot;
      // 8-bit quantization leaves a few hundredths on pure pixels.
      if (w < 0.02) continue;
      w = std::min(w, 1.0);
      sw += w;
      su += w * u;
      sv += w * v;
    }
  if (coverage_px) *coverage_px = sw;
  return {su / sw, sv / sw};
}

}  // namespace ceilpose::sim::testing
