#include "core/small_angle.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace ceilpose {
namespace {

// The series must be std::sin's and std::cos's to an ulp or two wherever
// it is used, both signs, down to 0 (exactly 0 and 1 there, as a still
// camera's rows need), and hand larger angles and NaN to the library.
TEST(SmallAngle, SineAndCosineAreWithinTwoUlpsOfTheLibrarys) {
  EXPECT_LE(kSmallAngle_rad, 0.15);
  double worst_sin_ulps = 0.0, worst_cos_ulps = 0.0;
  for (int i = -30000; i <= 30000; ++i) {
    const double a = kSmallAngle_rad * i / 30000.0;
    double s = 0.0, c = 0.0;
    small_angle_sincos(a, &s, &c);
    const double sin_ulp = std::nextafter(std::abs(std::sin(a)), 1.0) - std::abs(std::sin(a));
    const double cos_ulp = std::nextafter(std::cos(a), 0.0) - std::cos(a);
    if (a != 0.0) worst_sin_ulps = std::max(worst_sin_ulps, std::abs(s - std::sin(a)) / sin_ulp);
    worst_cos_ulps = std::max(worst_cos_ulps, std::abs(c - std::cos(a)) / std::abs(cos_ulp));
  }
  EXPECT_LE(worst_sin_ulps, 2.0);
  EXPECT_LE(worst_cos_ulps, 2.0);
  double s = 1.0, c = 0.0;
  small_angle_sincos(0.0, &s, &c);
  EXPECT_EQ(s, 0.0);
  EXPECT_EQ(c, 1.0);
  for (double a : {0.2, -1.0, 3.0, 100.0}) {
    small_angle_sincos(a, &s, &c);
    EXPECT_EQ(s, std::sin(a)) << a;
    EXPECT_EQ(c, std::cos(a)) << a;
  }
  small_angle_sincos(std::numeric_limits<double>::quiet_NaN(), &s, &c);
  EXPECT_TRUE(std::isnan(s) && std::isnan(c));
}

}  // namespace
}  // namespace ceilpose
