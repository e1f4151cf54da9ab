#include "core/small_matrix.h"

#include <gtest/gtest.h>

#include <random>

namespace ceilpose {
namespace {

constexpr int kN = 10;
using Matrix = std::array<double, kN * kN>;
using Vector = std::array<double, kN>;

// A random SPD matrix J^T J + I with J 14 x 10, as the fits' normal
// equations are.
Matrix random_spd(std::mt19937* rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::array<double, 14 * kN> j{};
  for (double& v : j) v = g(*rng);
  Matrix a{};
  for (int r = 0; r < kN; ++r)
    for (int c = 0; c < kN; ++c) {
      for (int k = 0; k < 14; ++k) a[r * kN + c] += j[k * kN + r] * j[k * kN + c];
      if (r == c) a[r * kN + c] += 1.0;
    }
  return a;
}

// The active block is solved to rounding and the others are exactly zero,
// whichever unknowns are active: the fits free 3 to 10 of their 10.
TEST(SolveSpd, SolvesTheActiveBlockAndGivesTheOthersZero) {
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    const Matrix a = random_spd(&rng);
    Vector b{};
    for (double& v : b) v = g(rng);
    std::array<bool, kN> active{};
    for (int i = 0; i < kN; ++i) active[i] = (trial + i) % 3 != 0 || trial % 5 == 0;
    Vector x{};
    ASSERT_TRUE(solve_spd<kN>(a, active, b, &x));
    for (int i = 0; i < kN; ++i) {
      if (!active[i]) {
        EXPECT_EQ(x[i], 0.0) << "inactive unknown " << i;
        continue;
      }
      double r = -b[i];
      for (int k = 0; k < kN; ++k)
        if (active[k]) r += a[i * kN + k] * x[k];
      EXPECT_NEAR(r, 0.0, 1e-11) << "trial " << trial << " row " << i;
    }
  }
}

// The inactive rows and columns are not read: what they hold does not
// change the answer by a bit.
TEST(SolveSpd, IgnoresWhatTheInactiveRowsHold) {
  std::mt19937 rng(11);
  const Matrix a = random_spd(&rng);
  const Vector b{1, -2, 3, -4, 5, -6, 7, -8, 9, -10};
  const std::array<bool, kN> active{true, false, true, true, false, true, false, false, true, true};
  Matrix junk = a;
  Vector junk_b = b;
  for (int i = 0; i < kN; ++i) {
    if (active[i]) continue;
    junk_b[i] = 1e30;
    for (int k = 0; k < kN; ++k) junk[i * kN + k] = junk[k * kN + i] = -1e30;
  }
  Vector x{}, y{};
  ASSERT_TRUE(solve_spd<kN>(a, active, b, &x));
  ASSERT_TRUE(solve_spd<kN>(junk, active, junk_b, &y));
  EXPECT_EQ(x, y);
}

// A block that is not positive definite is refused, and none active is
// the empty solve.
TEST(SolveSpd, RefusesABlockThatIsNotPositiveDefinite) {
  std::array<double, 9> a{1, 2, 0, 2, 1, 0, 0, 0, 1};  // eigenvalues -1, 1, 3
  std::array<double, 3> x{};
  EXPECT_FALSE(solve_spd<3>(a, {true, true, true}, {1, 1, 1}, &x));
  EXPECT_TRUE(solve_spd<3>(a, {true, false, true}, {1, 1, 1}, &x));
  EXPECT_EQ(x, (std::array<double, 3>{1, 0, 1}));
  EXPECT_TRUE(solve_spd<3>(a, {false, false, false}, {1, 1, 1}, &x));
  EXPECT_EQ(x, (std::array<double, 3>{0, 0, 0}));
  std::array<double, 9> nan_diag{NAN, 0, 0, 0, 1, 0, 0, 0, 1};
  EXPECT_FALSE(solve_spd<3>(nan_diag, {true, true, true}, {1, 1, 1}, &x));
}

}  // namespace
}  // namespace ceilpose
