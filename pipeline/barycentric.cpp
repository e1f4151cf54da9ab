#include "pipeline/barycentric.h"

#include <array>
#include <cmath>

namespace ceilpose {
namespace {

// Triangles are searched among at most this many markers (560 triples).
constexpr int kMaxCandidates = 16;

}  // namespace

// For a level camera the map from the ceiling plane to the (level,
// normalized) image plane is a similarity, so areal coordinates are
// preserved: if q = Σ λk·pk in the image with Σ λk = 1, the ceiling point
// imaged at q is Σ λk·Wk. q = (0, 0) is the image of the point straight above
// the lens (the principal point when the camera is level), so Σ λk·Wk is the
// lens's (x, y). λ solves the 2x2 system of the thesis:
//   λ1 = ((y2−y3)(qx−x3) + (x3−x2)(qy−y3)) / det,
//   λ2 = ((y3−y1)(qx−x3) + (x1−x3)(qy−y3)) / det,  λ3 = 1 − λ1 − λ2,
//   det = (y2−y3)(x1−x3) + (x3−x2)(y1−y3).
// The triangle chosen is the largest one containing q (interpolation); if
// none contains it, the largest (the least amplified extrapolation).
bool solve_barycentric(const ViewGeometry& view, const PositioningParams& params,
                       std::span<const MarkerFix> fixes, std::span<const bool> use, Pose2D* robot,
                       std::array<int, 3>* chosen) {
  std::array<int, kMaxCandidates> cand{};
  int n = 0;
  for (int k = 0; k < static_cast<int>(fixes.size()) && n < kMaxCandidates; ++k) {
    if (use[k]) cand[n++] = k;
  }
  if (n < 3) return false;
  // Normalized image area to ceiling area in grid units².
  const double units_per_n = view.depth_m() / view.layout().grid_m;
  const double min_det = 2.0 * params.barycentric_min_area_units2 / (units_per_n * units_per_n);
  int best[3] = {-1, -1, -1};
  bool best_contains = false;
  double best_det = 0.0;
  std::array<double, 3> best_lambda{};
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      for (int c = b + 1; c < n; ++c) {
        const MarkerFix& p1 = fixes[cand[a]];
        const MarkerFix& p2 = fixes[cand[b]];
        const MarkerFix& p3 = fixes[cand[c]];
        const double det = (p2.centre_y_n - p3.centre_y_n) * (p1.centre_x_n - p3.centre_x_n) +
                           (p3.centre_x_n - p2.centre_x_n) * (p1.centre_y_n - p3.centre_y_n);
        if (std::abs(det) < min_det) continue;
        const double qx = -p3.centre_x_n, qy = -p3.centre_y_n;
        const double l1 =
            ((p2.centre_y_n - p3.centre_y_n) * qx + (p3.centre_x_n - p2.centre_x_n) * qy) / det;
        const double l2 =
            ((p3.centre_y_n - p1.centre_y_n) * qx + (p1.centre_x_n - p3.centre_x_n) * qy) / det;
        const double l3 = 1.0 - l1 - l2;
        const bool contains = l1 >= 0.0 && l2 >= 0.0 && l3 >= 0.0;
        const bool better =
            (contains && !best_contains) || (contains == best_contains && std::abs(det) > best_det);
        if (!better) continue;
        best[0] = cand[a];
        best[1] = cand[b];
        best[2] = cand[c];
        best_contains = contains;
        best_det = std::abs(det);
        best_lambda = {l1, l2, l3};
      }
  if (best[0] < 0) return false;
  double x = 0.0, y = 0.0, sin_sum = 0.0, cos_sum = 0.0;
  for (int k = 0; k < 3; ++k) {
    const MarkerFix& f = fixes[best[k]];
    x += best_lambda[k] * f.world_x_m;
    y += best_lambda[k] * f.world_y_m;
    // Thesis: heading from the markers; averaged on the circle.
    sin_sum += std::sin(f.cam_yaw_rad);
    cos_sum += std::cos(f.cam_yaw_rad);
  }
  *robot = view.robot_from_camera(x, y, std::atan2(sin_sum, cos_sum));
  *chosen = {best[0], best[1], best[2]};
  return true;
}

}  // namespace ceilpose
