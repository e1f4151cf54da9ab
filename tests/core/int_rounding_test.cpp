#include "core/int_rounding.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace ceilpose {
namespace {

// The hot paths' floor and ceiling must be std::floor's and std::ceil's
// exactly, or an edge profile's pixels would move: negative values, whole
// numbers, and the neighbours of both.
TEST(IntRounding, FloorAndCeilAreStdsOnEitherSideOfZeroAndOfWholeNumbers) {
  for (int n = -5; n <= 5; ++n) {
    const double whole = n;
    for (double x : {whole, std::nextafter(whole, -1e9), std::nextafter(whole, 1e9), whole + 0.25,
                     whole + 0.5, whole - 0.5, whole + 0.999}) {
      SCOPED_TRACE(x);
      EXPECT_EQ(floor_int(x), static_cast<int>(std::floor(x)));
      EXPECT_EQ(ceil_int(x), static_cast<int>(std::ceil(x)));
    }
  }
  EXPECT_EQ(floor_int(-0.0), 0);
  EXPECT_EQ(ceil_int(-0.0), 0);
  EXPECT_EQ(floor_int(1279.999999), 1279);
  EXPECT_EQ(ceil_int(-1e-300), 0);
}

}  // namespace
}  // namespace ceilpose
