#include "sim/trajectory.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace ceilpose::sim {
namespace {

constexpr double kPi = std::numbers::pi;

// A path is driven like a turtle: straight runs and turns of a fixed
// radius, so the speed is exact and the yaw rate never exceeds v / radius.
struct Segment {
  double length_m;
  double turn_rad;  // total heading change over the segment; 0 for a straight run
};

struct Turtle {
  double x_m, y_m, heading_rad;
  // Advances along `seg` by `s_m` (0 <= s_m <= seg.length_m).
  void advance(const Segment& seg, double s_m) {
    if (seg.turn_rad == 0.0) {
      x_m += s_m * std::cos(heading_rad);
      y_m += s_m * std::sin(heading_rad);
      return;
    }
    const double radius_m = seg.length_m / std::abs(seg.turn_rad);
    const double side = seg.turn_rad > 0.0 ? 1.0 : -1.0;  // left (CCW) or right
    const double dh = side * s_m / radius_m;
    // Turning centre to the left (or right) of the heading.
    const double cx = x_m - side * radius_m * std::sin(heading_rad);
    const double cy = y_m + side * radius_m * std::cos(heading_rad);
    heading_rad += dh;
    x_m = cx + side * radius_m * std::sin(heading_rad);
    y_m = cy - side * radius_m * std::cos(heading_rad);
  }
};

}  // namespace

Pose2D trajectory_pose(const CeilingLayout& layout, double t_s) {
  // A patrol loop over the grid: East–West lanes two grid units apart joined
  // by U-turns of one grid unit radius, then back along the western edge.
  // For the default 8 x 8 grid: lanes at y = 0.5, 2.5, 4.5, 6.5 g.
  const double g = layout.grid_m;
  const int n = layout.codes();
  int lanes = std::max(2, (n - 2) / 2 + 1);
  if (lanes % 2 != 0) --lanes;  // an even count ends the lanes on the West side
  const double lane_m = std::max(0.0, (n - 4) * g);
  const double turn_m = kPi * g;
  std::vector<Segment> path;  // a few segments, built per call (never per frame)
  for (int k = 0; k < lanes; ++k) {
    path.push_back({lane_m, 0.0});
    if (k + 1 < lanes) path.push_back({turn_m, k % 2 == 0 ? kPi : -kPi});
  }
  const double west_run_m = (2.0 * (lanes - 1) - 2.0) * g;
  path.push_back({0.5 * turn_m, 0.5 * kPi});
  path.push_back({std::max(0.0, west_run_m), 0.0});
  path.push_back({0.5 * turn_m, 0.5 * kPi});

  double total_m = 0.0;
  for (const Segment& s : path) total_m += s.length_m;
  double s_m = std::fmod(kWalkingSpeed_mps * t_s, total_m);
  if (s_m < 0.0) s_m += total_m;
  Turtle turtle{1.5 * g, 0.5 * g, 0.0};
  for (const Segment& seg : path) {
    const double step_m = std::min(s_m, seg.length_m);
    turtle.advance(seg, step_m);
    s_m -= step_m;
    if (s_m <= 0.0) break;
  }
  return {turtle.x_m, turtle.y_m, wrap_angle_rad(turtle.heading_rad)};
}

}  // namespace ceilpose::sim
