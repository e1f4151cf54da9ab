#include "pipeline/accuracy_metrics.h"

#include <gtest/gtest.h>

#include <numbers>

namespace ceilpose {
namespace {

constexpr double kGrid_m = 0.6096;

PoseEstimate estimate_at(double x, double y, double yaw) {
  PoseEstimate e;
  e.valid = true;
  e.pose = {x, y, yaw};
  e.mode = PositioningMode::kLeastSquares;
  return e;
}

TEST(AccuracyMetrics, AvailabilityCountsOnlyFramesWithAWholeMarker) {
  AccuracyAccumulator acc(kGrid_m);
  acc.add({1, 1, 0}, true, estimate_at(1, 1, 0));
  acc.add({1, 1, 0}, true, PoseEstimate{});
  acc.add({1, 1, 0}, false, PoseEstimate{});
  const AccuracyReport r = acc.report();
  EXPECT_EQ(r.frames, 3);
  EXPECT_EQ(r.frames_with_whole, 2);
  EXPECT_DOUBLE_EQ(r.availability, 0.5);
  EXPECT_EQ(r.valid_without_whole, 0);
}

TEST(AccuracyMetrics, ValidPoseWithoutWholeMarkerIsCounted) {
  AccuracyAccumulator acc(kGrid_m);
  acc.add({1, 1, 0}, false, estimate_at(1, 1, 0));
  EXPECT_EQ(acc.report().valid_without_whole, 1);
}

TEST(AccuracyMetrics, WithinCriterionIsPerAxisInGridUnits) {
  AccuracyAccumulator acc(kGrid_m);
  const double in = 0.049 * kGrid_m, out = 0.051 * kGrid_m;
  acc.add({0, 0, 0}, true, estimate_at(in, in, 0));   // both within
  acc.add({0, 0, 0}, true, estimate_at(out, 0, 0));   // x out
  acc.add({0, 0, 0}, true, estimate_at(0, -out, 0));  // y out
  acc.add({0, 0, 0}, true, estimate_at(0, 0, 0));
  const AccuracyReport r = acc.report();
  EXPECT_DOUBLE_EQ(r.within_both, 0.5);
  EXPECT_DOUBLE_EQ(r.within_x, 0.75);
  EXPECT_DOUBLE_EQ(r.within_y, 0.75);
}

TEST(AccuracyMetrics, GrossErrorIsQuarterGridUnitOrFiveDegrees) {
  AccuracyAccumulator acc(kGrid_m);
  const double deg = std::numbers::pi / 180.0;
  acc.add({0, 0, 0}, true, estimate_at(0.24 * kGrid_m, 0, 4.9 * deg));             // not gross
  acc.add({0, 0, 0}, true, estimate_at(0.26 * kGrid_m, 0, 0));                     // position
  acc.add({0, 0, 3.1}, true, estimate_at(0, 0, wrap_angle_rad(3.1 + 5.1 * deg)));  // yaw, across pi
  EXPECT_EQ(acc.report().gross, 2);
}

TEST(AccuracyMetrics, YawErrorWrapsAcrossPi) {
  AccuracyAccumulator acc(kGrid_m);
  acc.add({0, 0, std::numbers::pi - 0.001}, true, estimate_at(0, 0, -std::numbers::pi + 0.001));
  EXPECT_NEAR(acc.report().yaw_p99_deg, 0.002 * 180.0 / std::numbers::pi, 1e-9);
  EXPECT_EQ(acc.report().gross, 0);
}

TEST(AccuracyMetrics, MedianAndP99AreNearestRankOfPositionErrors) {
  AccuracyAccumulator acc(kGrid_m);
  for (int k = 1; k <= 100; ++k) acc.add({0, 0, 0}, true, estimate_at(0.0001 * k, 0, 0));
  const AccuracyReport r = acc.report();
  EXPECT_NEAR(r.median_error_mm, 5.0, 1e-9);
  EXPECT_NEAR(r.p99_error_mm, 9.9, 1e-9);
  EXPECT_NEAR(r.max_error_mm, 10.0, 1e-9);
}

}  // namespace
}  // namespace ceilpose
