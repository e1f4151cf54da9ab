#include "pipeline/marker_pairing.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/length_2d.h"

// Two rectangles of one marker share a long edge, so (SPEC §2): their long
// axes are parallel, the vector between their centres is perpendicular to
// them and as long as one rectangle is wide (5 in, i.e. 5/12 of the long
// side measured in the same image), and their areas and long sides are
// equal. Every red/green combination that passes all five tests within tolerance is a
// candidate; candidates are taken best score first, each rectangle once, so
// a clutter blob next to a marker cannot steal its partner from a better fit.

namespace ceilpose {
namespace {

// Difference of two axis directions, folded into (−π/2, π/2].
double axis_difference_rad(double a, double b) {
  double d = std::remainder(a - b, std::numbers::pi);
  if (d <= -0.5 * std::numbers::pi) d += std::numbers::pi;
  return d;
}

}  // namespace

MarkerPairer::MarkerPairer(int max_rectangles) {
  const auto n = static_cast<size_t>(std::max(1, max_rectangles));
  candidates_.resize(n * n / 4 + n);
  used_.resize(n);
}

int MarkerPairer::pair(std::span<const RectangleCandidate> rects, const CeilingLayout& layout,
                       const DetectorParams& params, std::span<MarkerPair> out) {
  if (rects.size() > used_.size()) rects = rects.first(used_.size());
  const double width_per_length = layout.rect_width_m / layout.rect_height_m;
  const double sin_tol = std::sin(params.pair_angle_tolerance_rad);
  size_t n = 0;
  for (size_t i = 0; i < rects.size(); ++i) {
    const RectangleCandidate& red = rects[i];
    if (red.cls != PixelClass::kRed) continue;
    const double ax = std::cos(red.axis_rad), ay = std::sin(red.axis_rad);
    for (size_t j = 0; j < rects.size() && n < candidates_.size(); ++j) {
      const RectangleCandidate& green = rects[j];
      if (green.cls != PixelClass::kGreen) continue;
      const double du = green.cx - red.cx, dv = green.cy - red.cy;
      const double dist = length_2d(du, dv);
      const double expected = 0.5 * (red.long_px + green.long_px) * width_per_length;
      if (dist <= 0.0 || expected <= 0.0) continue;
      const double dist_err = std::abs(dist / expected - 1.0);
      if (dist_err > params.pair_distance_tolerance) continue;
      const double area_err = std::abs(red.area_px / green.area_px - 1.0);
      if (area_err > params.pair_area_tolerance) continue;
      const double length_err = std::abs(red.long_px / green.long_px - 1.0);
      if (length_err > params.pair_length_tolerance) continue;
      const double parallel_err = std::abs(axis_difference_rad(red.axis_rad, green.axis_rad));
      if (parallel_err > params.pair_angle_tolerance_rad) continue;
      const double along = std::abs(du * ax + dv * ay) / dist;  // sine of the off-normal angle
      if (along > sin_tol) continue;
      candidates_[n++] = MarkerPair{
          static_cast<int>(i), static_cast<int>(j),
          dist_err / params.pair_distance_tolerance + area_err / params.pair_area_tolerance +
              parallel_err / params.pair_angle_tolerance_rad + along / sin_tol};
    }
  }
  std::sort(candidates_.begin(), candidates_.begin() + static_cast<std::ptrdiff_t>(n),
            [](const MarkerPair& a, const MarkerPair& b) { return a.score < b.score; });
  std::fill(used_.begin(), used_.begin() + static_cast<std::ptrdiff_t>(rects.size()), 0);
  int count = 0;
  for (size_t k = 0; k < n && count < static_cast<int>(out.size()); ++k) {
    const MarkerPair& p = candidates_[k];
    if (used_[p.red] || used_[p.green]) continue;
    used_[p.red] = used_[p.green] = 1;
    out[count++] = p;
  }
  return count;
}

}  // namespace ceilpose
