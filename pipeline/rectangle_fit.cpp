#include "pipeline/rectangle_fit.h"

#include <algorithm>
#include <cmath>

// A filled a × b rectangle has central moments a²/12 and b²/12 along its
// axes. The eigenvalues λ1 ≥ λ2 of the blob's moment matrix
//   λ = (mu20 + mu02)/2 ± sqrt(((mu20 − mu02)/2)² + mu11²)
// therefore give its sides as sqrt(12 λ + 1): the +1 restores the 1/12 that
// each unit pixel square adds to the continuous moment and that the pixel
// centres miss. The long axis lies along θ with tan 2θ = 2 mu11/(mu20 − mu02)
// (the thesis's orientation formula). Fill = area / (long × short) is 1 for a
// filled rectangle and falls for rings, L-shapes and joined blobs.

namespace ceilpose {

RectangleModel make_rectangle_model(const CameraIntrinsics& intrinsics, const CameraMount& mount,
                                    const CeilingLayout& layout) {
  RectangleModel m;
  const double distance_m = std::max(1e-3, layout.height_m - mount.lens_height_m);
  m.px_per_m = 0.5 * (intrinsics.fx + intrinsics.fy) / distance_m;
  m.expected_long_px = layout.rect_height_m * m.px_per_m;
  m.expected_short_px = layout.rect_width_m * m.px_per_m;
  m.expected_area_px = m.expected_long_px * m.expected_short_px;
  return m;
}

int fit_rectangles(std::span<const Component> components, const RectangleModel& model,
                   const DetectorParams& params, std::span<RectangleCandidate> out) {
  const double min_area =
      std::max<double>(params.min_rect_area_px, params.area_min_ratio * model.expected_area_px);
  const double max_area = params.area_max_ratio * model.expected_area_px;
  int count = 0;
  for (size_t k = 0; k < components.size() && count < static_cast<int>(out.size()); ++k) {
    const Component& c = components[k];
    if (c.cls != PixelClass::kRed && c.cls != PixelClass::kGreen) continue;
    if (c.area_px < min_area || c.area_px > max_area) continue;
    const double mean = 0.5 * (c.mu20 + c.mu02);
    const double half_diff = 0.5 * (c.mu20 - c.mu02);
    const double root = std::sqrt(half_diff * half_diff + c.mu11 * c.mu11);
    const double long_px = std::sqrt(12.0 * (mean + root) + 1.0);
    const double short_px = std::sqrt(std::max(0.0, 12.0 * (mean - root) + 1.0));
    if (short_px <= 0.0) continue;
    const double aspect = short_px / long_px;
    if (aspect < params.aspect_min || aspect > params.aspect_max) continue;
    const double fill = c.area_px / (long_px * short_px);
    if (fill < params.fill_min || fill > params.fill_max) continue;
    RectangleCandidate& r = out[count++];
    r.cls = c.cls;
    r.component = static_cast<int>(k);
    r.cx = c.cx;
    r.cy = c.cy;
    r.axis_rad = c.orientation_rad();
    r.long_px = long_px;
    r.short_px = short_px;
    r.area_px = c.area_px;
    r.dark_px = c.dark_px;
    r.fill = fill;
    r.touches_border = c.touches_border;
  }
  return count;
}

}  // namespace ceilpose
