#include "sim/trajectory.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace ceilpose::sim {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr int kArcSegments = 2048;

// A 1:2 Lissajous figure over the grid interior. Its velocity never vanishes
// (x' = 0 only at p = 1/4, 3/4, where y' != 0), so the robot always faces
// along its path and the yaw is smooth.
struct Lissajous {
  double centre_m, amplitude_m;
  void at(double p, double* x, double* y) const {
    *x = centre_m + amplitude_m * std::sin(kTwoPi * p);
    *y = centre_m + amplitude_m * std::sin(2.0 * kTwoPi * p + 0.25 * std::numbers::pi);
  }
  double heading_rad(double p) const {
    const double dx = std::cos(kTwoPi * p);
    const double dy = 2.0 * std::cos(2.0 * kTwoPi * p + 0.25 * std::numbers::pi);
    return std::atan2(dy, dx);
  }
};

}  // namespace

Pose2D trajectory_pose(const CeilingLayout& layout, double t_s) {
  const double span_m = (layout.codes() - 1) * layout.grid_m;
  const Lissajous curve{0.5 * span_m, 0.38 * span_m};
  // Constant speed: parametrize by arc length through a table of the
  // cumulative length (cheap; built per call, never in a per-frame path).
  std::array<double, kArcSegments + 1> arc_m{};
  double px = 0.0, py = 0.0;
  curve.at(0.0, &px, &py);
  for (int k = 1; k <= kArcSegments; ++k) {
    double x = 0.0, y = 0.0;
    curve.at(static_cast<double>(k) / kArcSegments, &x, &y);
    arc_m[k] = arc_m[k - 1] + std::hypot(x - px, y - py);
    px = x;
    py = y;
  }
  const double length_m = arc_m[kArcSegments];
  double s = std::fmod(kWalkingSpeed_mps * t_s, length_m);
  if (s < 0.0) s += length_m;
  const auto it = std::upper_bound(arc_m.begin(), arc_m.end(), s);
  const int k = std::clamp(static_cast<int>(it - arc_m.begin()) - 1, 0, kArcSegments - 1);
  const double seg = arc_m[k + 1] - arc_m[k];
  const double p = (k + (seg > 0.0 ? (s - arc_m[k]) / seg : 0.0)) / kArcSegments;
  Pose2D pose;
  curve.at(p, &pose.x_m, &pose.y_m);
  pose.yaw_rad = wrap_angle_rad(curve.heading_rad(p));
  return pose;
}

}  // namespace ceilpose::sim
