#include "pipeline/change_of_axes.h"

#include <gtest/gtest.h>

#include <numbers>

#include "pipeline/pipeline_config.h"
#include "pipeline/positioner.h"
#include "positioning_support.h"

namespace ceilpose {
namespace {

TEST(ChangeOfAxes, RecoversPoseFromOneExactMarkerAtAnyHeading) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  for (double yaw = -3.0; yaw <= 3.1; yaw += 0.5) {
    const Pose2D robot{1.7, 2.1, yaw};
    const auto markers = testing::observe(view, robot);
    ASSERT_FALSE(markers.empty());
    const PoseEstimate est = positioner.solve(markers, PositioningMode::kChangeOfAxes);
    ASSERT_TRUE(est.valid) << "yaw " << yaw;
    EXPECT_EQ(est.mode, PositioningMode::kChangeOfAxes);
    EXPECT_EQ(est.markers, 1);
    EXPECT_NEAR(est.pose.x_m, robot.x_m, 1e-9);
    EXPECT_NEAR(est.pose.y_m, robot.y_m, 1e-9);
    EXPECT_NEAR(wrap_angle_rad(est.pose.yaw_rad - yaw), 0.0, 1e-9);
  }
}

TEST(ChangeOfAxes, RemovesMountOffsetAndMountingYaw) {
  PipelineConfig config;
  config.mount.offset_forward_m = 0.12;
  config.mount.offset_left_m = -0.05;
  config.mount.yaw_rad = 0.3;
  Positioner positioner(config);
  testing::SyntheticView view;
  view.mount = config.mount;
  const Pose2D robot{2.0, 1.2, 2.2};
  const PoseEstimate est =
      positioner.solve(testing::observe(view, robot), PositioningMode::kChangeOfAxes);
  ASSERT_TRUE(est.valid);
  EXPECT_NEAR(est.pose.x_m, robot.x_m, 1e-9);
  EXPECT_NEAR(est.pose.y_m, robot.y_m, 1e-9);
  EXPECT_NEAR(est.pose.yaw_rad, robot.yaw_rad, 1e-9);
}

TEST(ChangeOfAxes, CorrectsForConfiguredNominalTiltAndDistortion) {
  PipelineConfig config;
  config.mount.tilt_x_rad = 0.04;
  config.mount.tilt_y_rad = -0.03;
  config.intrinsics.distortion = {-0.1, 0.02, 0.001, -0.001, 0.0};
  Positioner positioner(config);
  testing::SyntheticView view;
  view.mount = config.mount;
  view.intrinsics = config.intrinsics;
  const Pose2D robot{2.5, 3.0, -1.0};
  const PoseEstimate est =
      positioner.solve(testing::observe(view, robot), PositioningMode::kChangeOfAxes);
  ASSERT_TRUE(est.valid);
  EXPECT_NEAR(est.pose.x_m, robot.x_m, 1e-7);
  EXPECT_NEAR(est.pose.y_m, robot.y_m, 1e-7);
  EXPECT_NEAR(est.pose.yaw_rad, robot.yaw_rad, 1e-7);
}

TEST(ChangeOfAxes, ScaleIsPixelsPerGridUnitOfSpec) {
  PipelineConfig config;
  const ViewGeometry view(config);
  // SPEC §3: "one grid unit spans about 151 px" at the default heights.
  EXPECT_NEAR(view.pixels_per_grid_unit(), 151.43, 0.01);
}

TEST(ChangeOfAxes, RejectsCodeOutsideTheLayout) {
  PipelineConfig config;
  const ViewGeometry view(config);
  testing::SyntheticView sv;
  auto markers = testing::observe(sv, {1.0, 1.0, 0.0});
  ASSERT_FALSE(markers.empty());
  markers[0].code_i = 8;
  MarkerFix fix;
  EXPECT_FALSE(marker_fix(view, markers[0], 0, {}, &fix));
}

}  // namespace
}  // namespace ceilpose
