#include <gtest/gtest.h>

#include <cmath>

#include "pipeline/pipeline_config.h"
#include "pipeline/positioner.h"
#include "positioning_support.h"

namespace ceilpose {
namespace {

TEST(Positioning, AutoUsesLeastSquaresOnAFullView) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  const Pose2D robot{2.0, 2.0, 1.0};
  const PoseEstimate est = positioner.solve(testing::observe(view, robot), PositioningMode::kAuto);
  ASSERT_TRUE(est.valid);
  EXPECT_EQ(est.mode, PositioningMode::kLeastSquares);
  EXPECT_NEAR(est.pose.x_m, robot.x_m, 1e-6);
}

TEST(Positioning, AutoFallsBackToThesisModeWhenTooFewPoints) {
  PipelineConfig config;
  config.positioning.lsq_min_points = 1000;
  Positioner positioner(config);
  testing::SyntheticView view;
  const Pose2D robot{2.0, 2.0, 1.0};
  auto markers = testing::observe(view, robot);
  PoseEstimate est = positioner.solve(markers, PositioningMode::kAuto);
  ASSERT_TRUE(est.valid);
  EXPECT_EQ(est.mode, PositioningMode::kBarycentric);
  markers.resize(1);
  est = positioner.solve(markers, PositioningMode::kAuto);
  ASSERT_TRUE(est.valid);
  EXPECT_EQ(est.mode, PositioningMode::kChangeOfAxes);
  EXPECT_NEAR(est.pose.y_m, robot.y_m, 1e-9);
}

TEST(Positioning, DepthScaleIsOneWhenTheHeightsAreRight) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  view.mount.tilt_x_rad = 0.05;  // 3 degrees the configuration does not know
  view.noise_px = 0.2;
  for (const Pose2D robot : {Pose2D{2.0, 2.0, 1.0}, Pose2D{0.7, 3.9, -2.5}}) {
    const PoseEstimate est =
        positioner.solve(testing::observe(view, robot), PositioningMode::kAuto);
    ASSERT_TRUE(est.valid);
    EXPECT_NEAR(est.depth_scale, 1.0, 0.03);
  }
}

TEST(Positioning, HeightsThatDisagreeWithTheMarkersSpacingAreRefused) {
  // The camera sees a ceiling 2.5 m above the lens; the configuration says
  // SPEC's 2.134 m.
  testing::SyntheticView view;
  view.layout.height_m = 3.0;
  view.mount.lens_height_m = 0.5;
  const Pose2D robot{2.0, 2.0, 1.0};
  const auto markers = testing::observe(view, robot);
  ASSERT_GE(markers.size(), 2u);

  PipelineConfig config;
  Positioner positioner(config);
  for (const PositioningMode mode :
       {PositioningMode::kAuto, PositioningMode::kLeastSquares, PositioningMode::kBarycentric}) {
    const PoseEstimate est = positioner.solve(markers, mode);
    EXPECT_FALSE(est.valid);
    EXPECT_EQ(est.refusal, Refusal::kWrongHeights);
    EXPECT_NEAR(est.depth_scale, 2.5 / (2.4384 - 0.3048), 0.01);
  }

  // Switched off, the same view gives a pose again (one that the wrong
  // heights make inaccurate).
  config.positioning.max_depth_scale_error = 0.0;
  Positioner unchecked(config);
  EXPECT_TRUE(unchecked.solve(markers, PositioningMode::kAuto).valid);
}

TEST(Positioning, NoMarkersGivesInvalidPose) {
  PipelineConfig config;
  Positioner positioner(config);
  for (auto mode : {PositioningMode::kAuto, PositioningMode::kChangeOfAxes,
                    PositioningMode::kBarycentric, PositioningMode::kLeastSquares}) {
    const PoseEstimate est = positioner.solve({}, mode);
    EXPECT_FALSE(est.valid);
    EXPECT_EQ(est.refusal, Refusal::kNoWholeMarker) << to_string(mode);
  }
}

TEST(Positioning, OnlyPartialMarkersGivesInvalidPose) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  view.include_partial = true;
  auto markers = testing::observe(view, {2.0, 2.0, 0.3});
  std::vector<MarkerObservation> partial;
  for (const auto& m : markers)
    if (!m.whole) partial.push_back(m);
  ASSERT_FALSE(partial.empty());
  const PoseEstimate est = positioner.solve(partial, PositioningMode::kAuto);
  EXPECT_FALSE(est.valid);
  EXPECT_EQ(est.refusal, Refusal::kNoWholeMarker);
}

TEST(Positioning, TwoDisagreeingMarkersGiveInvalidPose) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  auto markers = testing::observe(view, {2.0, 2.0, 0.3});
  markers.resize(2);
  markers[0].code_i ^= 4;
  const PoseEstimate est = positioner.solve(markers, PositioningMode::kAuto);
  EXPECT_FALSE(est.valid);
  EXPECT_EQ(est.refusal, Refusal::kInconsistentMarkers);
}

TEST(Positioning, ARequestedModeTheViewCannotServeIsTooFewMarkers) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  auto markers = testing::observe(view, {2.0, 2.0, 0.3});
  markers.resize(2);
  PoseEstimate est = positioner.solve(markers, PositioningMode::kBarycentric);
  EXPECT_FALSE(est.valid);
  EXPECT_EQ(est.refusal, Refusal::kTooFewMarkers);
  config.positioning.lsq_min_points = 1000;
  Positioner strict(config);
  est = strict.solve(markers, PositioningMode::kLeastSquares);
  EXPECT_FALSE(est.valid);
  EXPECT_EQ(est.refusal, Refusal::kTooFewMarkers);
  EXPECT_EQ(strict.solve(markers, PositioningMode::kAuto).refusal, Refusal::kNone)
      << "auto falls back to a thesis mode";
}

TEST(Positioning, ALoneMarkerWithUnclearDotsIsRefusedAsSuch) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  auto markers = testing::observe(view, {2.0, 2.0, 0.3});
  markers.resize(1);
  markers[0].quality = 0.3f;
  const PoseEstimate est = positioner.solve(markers, PositioningMode::kAuto);
  EXPECT_FALSE(est.valid);
  EXPECT_EQ(est.refusal, Refusal::kLoneMarkerUnclear);
  markers[0].quality = 0.9f;
  EXPECT_TRUE(positioner.solve(markers, PositioningMode::kAuto).valid);
}

TEST(Positioning, OutlierMarkerDoesNotMoveAnyMode) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  const Pose2D robot{2.3, 1.8, -2.0};
  auto markers = testing::observe(view, robot);
  ASSERT_GE(markers.size(), 5u);
  markers[0].code_j ^= 1;
  markers[4].code_i ^= 3;
  for (auto mode : {PositioningMode::kAuto, PositioningMode::kChangeOfAxes,
                    PositioningMode::kBarycentric, PositioningMode::kLeastSquares}) {
    const PoseEstimate est = positioner.solve(markers, mode);
    ASSERT_TRUE(est.valid) << to_string(mode);
    EXPECT_EQ(est.refusal, Refusal::kNone);
    EXPECT_LT(std::hypot(est.pose.x_m - robot.x_m, est.pose.y_m - robot.y_m), 1e-6)
        << to_string(mode);
  }
}

// The reconcile step says why each marker it does not believe was left out.
TEST(Positioning, ReconcileCountsWhyEachMarkerWasNotBelieved) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  auto markers = testing::observe(view, {2.3, 1.8, -2.0});
  ASSERT_GE(markers.size(), 6u);
  markers[0].code_j ^= 1;  // misread: grid-inconsistent
  markers[1].whole = false;
  markers[2].code_i = 40;  // outside the layout: not on the map
  EXPECT_EQ(positioner.reconcile(markers, {}), Refusal::kNone);
  const ReconcileCounts& c = positioner.reconcile_counts();
  EXPECT_EQ(c.inconsistent, 1);
  EXPECT_EQ(c.cut_off, 1);
  EXPECT_EQ(c.unmapped, 1);
  EXPECT_EQ(c.lone_unclear, 0);
  EXPECT_EQ(c.believed + c.rejected(), static_cast<int>(markers.size()));
  EXPECT_TRUE(positioner.position(markers, PositioningMode::kLeastSquares, {}).valid);
  EXPECT_EQ(positioner.reconcile_counts().residual, 0);
}

TEST(Positioning, NonFiniteObservationGivesInvalidNotGarbage) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  auto markers = testing::observe(view, {2.0, 2.0, 0.3});
  markers.resize(1);
  markers[0].red_u_px = NAN;
  for (auto mode :
       {PositioningMode::kAuto, PositioningMode::kChangeOfAxes, PositioningMode::kLeastSquares}) {
    const PoseEstimate est = positioner.solve(markers, mode);
    EXPECT_FALSE(est.valid) << to_string(mode);
  }
}

}  // namespace
}  // namespace ceilpose
