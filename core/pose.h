#pragma once
#include <cmath>
#include <numbers>

namespace ceilpose {

// Robot pose in the world frame `map` (SPEC §1): x East, y North, yaw from +x
// counter-clockwise, in (-pi, pi].
struct Pose2D {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

// Wraps an angle into (-pi, pi].
inline double wrap_angle_rad(double a) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  a = std::fmod(a, kTwoPi);
  if (a <= -std::numbers::pi) a += kTwoPi;
  if (a > std::numbers::pi) a -= kTwoPi;
  return a;
}

}  // namespace ceilpose
