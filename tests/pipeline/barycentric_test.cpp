#include "pipeline/barycentric.h"

#include <gtest/gtest.h>

#include "pipeline/pipeline_config.h"
#include "pipeline/positioner.h"
#include "positioning_support.h"

namespace ceilpose {
namespace {

TEST(Barycentric, RecoversPoseFromExactMarkers) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  for (const Pose2D robot :
       {Pose2D{1.0, 1.0, 0.0}, Pose2D{2.3, 1.6, 1.2}, Pose2D{3.1, 2.9, -2.5}}) {
    const PoseEstimate est =
        positioner.solve(testing::observe(view, robot), PositioningMode::kBarycentric);
    ASSERT_TRUE(est.valid);
    EXPECT_EQ(est.mode, PositioningMode::kBarycentric);
    EXPECT_EQ(est.markers, 3);
    EXPECT_NEAR(est.pose.x_m, robot.x_m, 1e-9);
    EXPECT_NEAR(est.pose.y_m, robot.y_m, 1e-9);
    EXPECT_NEAR(wrap_angle_rad(est.pose.yaw_rad - robot.yaw_rad), 0.0, 1e-9);
  }
}

TEST(Barycentric, InvalidWithFewerThanThreeMarkers) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  auto markers = testing::observe(view, {1.0, 1.0, 0.3});
  ASSERT_GE(markers.size(), 3u);
  markers.resize(2);
  EXPECT_FALSE(positioner.solve(markers, PositioningMode::kBarycentric).valid);
}

TEST(Barycentric, RefusesCollinearMarkers) {
  PipelineConfig config;
  const ViewGeometry view(config);
  testing::SyntheticView sv;
  const auto markers = testing::observe(sv, {1.2, 1.2, 0.0});
  // Three markers of one row are collinear: no triangle.
  std::vector<MarkerObservation> row;
  for (const auto& m : markers)
    if (m.code_j == 2) row.push_back(m);
  const auto fixes = testing::fixes_of(view, row);
  ASSERT_GE(fixes.size(), 3u);
  const bool use[kMaxMarkersPerFrame] = {true, true, true, true, true, true, true, true};
  Pose2D robot;
  std::array<int, 3> chosen{};
  EXPECT_FALSE(solve_barycentric(view, config.positioning, fixes, std::span(use, fixes.size()),
                                 &robot, &chosen));
}

TEST(Barycentric, SmallPixelNoiseGivesSmallError) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  view.noise_px = 0.3;
  const Pose2D robot{2.0, 2.2, 0.7};
  const PoseEstimate est =
      positioner.solve(testing::observe(view, robot), PositioningMode::kBarycentric);
  ASSERT_TRUE(est.valid);
  EXPECT_NEAR(est.pose.x_m, robot.x_m, 0.01);
  EXPECT_NEAR(est.pose.y_m, robot.y_m, 0.01);
}

}  // namespace
}  // namespace ceilpose
