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

namespace ceilpose::sim {
namespace {

// The drive's path around the grid centre, metres, as a function of the
// parameter u in [0, 2π): a figure of eight bent by a third harmonic per
// axis, curves of 0.35 m radius and up on the default grid, no cusp.
struct DrivePath {
  double cx_m, cy_m, scale;
  void at(double u, double* x_m, double* y_m) const {
    *x_m = cx_m + scale * (1.45 * std::sin(u) - 0.20 * std::sin(3.0 * u));
    *y_m = cy_m + scale * (1.15 * std::sin(2.0 * u + 0.3) + 0.10 * std::cos(3.0 * u));
  }
};

constexpr int kDriveSamples = 16384;

}  // namespace

Pose2D drive_pose(const CeilingLayout& layout, double t_s) {
  const double span_m = (layout.codes() - 1) * layout.grid_m;
  // Sized for the default 8 x 8 grid (span 4.27 m); smaller grids shrink it.
  const DrivePath path{0.5 * span_m, 0.5 * span_m, std::min(1.0, span_m / 4.267)};
  // Arc length along u of the unit-scale path, tabulated once per process
  // (a rolling-shutter frame asks for a pose per row): the speed profile is
  // given in metres per second, not in u per second.
  static const std::vector<double> unit_arc = [] {
    const DrivePath unit{0.0, 0.0, 1.0};
    std::vector<double> arc(kDriveSamples + 1, 0.0);
    double px = 0.0, py = 0.0;
    unit.at(0.0, &px, &py);
    for (int k = 1; k <= kDriveSamples; ++k) {
      double x = 0.0, y = 0.0;
      unit.at(2.0 * kPi * k / kDriveSamples, &x, &y);
      arc[k] = arc[k - 1] + std::hypot(x - px, y - py);
      px = x;
      py = y;
    }
    return arc;
  }();
  const double total_m = path.scale * unit_arc.back();
  // Speed between kDriveMinSpeed_mps and kDriveMaxSpeed_mps, one period
  // every kDriveSpeedPeriod_s: s(t) = ∫ v.
  const double mean = 0.5 * (kDriveMinSpeed_mps + kDriveMaxSpeed_mps);
  const double amp = 0.5 * (kDriveMaxSpeed_mps - kDriveMinSpeed_mps);
  const double w = 2.0 * kPi / kDriveSpeedPeriod_s;
  double s_m = std::fmod(mean * t_s - amp / w * std::sin(w * t_s), total_m);
  if (s_m < 0.0) s_m += total_m;
  const double s_unit = s_m / path.scale;
  const auto it = std::upper_bound(unit_arc.begin(), unit_arc.end(), s_unit);
  const int k = std::clamp(static_cast<int>(it - unit_arc.begin()) - 1, 0, kDriveSamples - 1);
  const double f = (s_unit - unit_arc[k]) / std::max(1e-12, unit_arc[k + 1] - unit_arc[k]);
  const double u = 2.0 * kPi * (k + f) / kDriveSamples;
  double x = 0.0, y = 0.0, xa = 0.0, ya = 0.0, xb = 0.0, yb = 0.0;
  path.at(u, &x, &y);
  path.at(u - 1e-6, &xa, &ya);
  path.at(u + 1e-6, &xb, &yb);
  // The robot drives forwards: its heading is the path's tangent.
  return {x, y, std::atan2(yb - ya, xb - xa)};
}

}  // namespace ceilpose::sim
