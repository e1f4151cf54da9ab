#include "pipeline/grid_consistency.h"

#include <cmath>

#include "core/length_2d.h"

namespace ceilpose {
namespace {

bool agree(const MarkerFix& a, const MarkerFix& b, double tolerance_m, double heading_rad) {
  const double dx = a.cam_x_m - b.cam_x_m, dy = a.cam_y_m - b.cam_y_m;
  return dx * dx + dy * dy <= tolerance_m * tolerance_m &&
         std::abs(wrap_angle_rad(a.cam_yaw_rad - b.cam_yaw_rad)) <= heading_rad;
}

}  // namespace

int grid_consistent_subset(const PositioningParams& params, double grid_m,
                           std::span<const MarkerFix> fixes, std::span<bool> inlier) {
  const int n = static_cast<int>(fixes.size());
  const double tolerance_m = params.grid_tolerance_units * grid_m;
  for (int k = 0; k < n; ++k) inlier[k] = false;
  if (n == 0) return 0;
  // Each marker's support is the set of markers agreeing with it; the best
  // seed has the largest support (ties: the tighter cluster).
  int best = -1, best_support = 0;
  double best_spread = 0.0;
  for (int k = 0; k < n; ++k) {
    int support = 0;
    double spread = 0.0;
    for (int m = 0; m < n; ++m) {
      if (!agree(fixes[k], fixes[m], tolerance_m, params.heading_tolerance_rad)) continue;
      ++support;
      spread += length_2d(fixes[k].cam_x_m - fixes[m].cam_x_m, fixes[k].cam_y_m - fixes[m].cam_y_m);
    }
    if (support > best_support || (support == best_support && spread < best_spread)) {
      best = k;
      best_support = support;
      best_spread = spread;
    }
  }
  // An equally supported seed that disagrees with the best one means two
  // rival readings of the ceiling: refuse rather than guess.
  for (int k = 0; k < n; ++k) {
    if (k == best || agree(fixes[k], fixes[best], tolerance_m, params.heading_tolerance_rad)) {
      continue;
    }
    int support = 0;
    for (int m = 0; m < n; ++m) {
      if (agree(fixes[k], fixes[m], tolerance_m, params.heading_tolerance_rad)) ++support;
    }
    if (support >= best_support) return 0;
  }
  for (int m = 0; m < n; ++m) {
    inlier[m] = agree(fixes[best], fixes[m], tolerance_m, params.heading_tolerance_rad);
  }
  return best_support;
}

}  // namespace ceilpose
