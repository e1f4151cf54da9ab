// Renderer::render_rolling (issue 16): each pixel row sees the robot at its
// own instant; a still robot or a zero readout renders exactly as a global
// shutter does.
#include <gtest/gtest.h>

#include <cstring>

#include "sim/renderer.h"
#include "sim/scenarios.h"

namespace ceilpose::sim {
namespace {

bool same_row(const Image& a, const Image& b, int row) {
  const ImageView va = a.view(), vb = b.view();
  return std::memcmp(va.data + static_cast<size_t>(row) * va.stride_bytes,
                     vb.data + static_cast<size_t>(row) * vb.stride_bytes,
                     static_cast<size_t>(va.width) * 3) == 0;
}

bool same_image(const Image& a, const Image& b) {
  for (int r = 0; r < a.view().height; ++r)
    if (!same_row(a, b, r)) return false;
  return true;
}

class RollingShutter : public ::testing::Test {
 protected:
  SceneOptions options_;
  Renderer renderer_{options_};
  CameraMount mount_;
  Effects effects_;
  Image global_, rolling_;
};

TEST_F(RollingShutter, AStillRobotOrNoReadoutIsTheGlobalShutterImageBitForBit) {
  effects_.read_noise_sigma = 2.0;
  const Pose2D still{1.3, 1.7, 0.4};
  renderer_.render(still, mount_, effects_, 7, &global_);
  renderer_.render_rolling([&](double) { return still; }, 0.025, mount_, effects_, 7, &rolling_);
  EXPECT_TRUE(same_image(global_, rolling_)) << "a still robot, 25 ms readout";
  auto moving = [](double dt_s) { return Pose2D{1.3 + 1.5 * dt_s, 1.7, 0.4 + 2.0 * dt_s}; };
  renderer_.render_rolling(moving, 0.0, mount_, effects_, 7, &rolling_);
  EXPECT_TRUE(same_image(global_, rolling_)) << "no readout";
}

TEST_F(RollingShutter, EachRowShowsTheRobotAtThatRowsInstant) {
  // 1.5 m/s East and 2 rad/s through a 25 ms readout: the ceiling moves
  // 37 mm (about 9 px) between the first row and the last.
  auto moving = [](double dt_s) { return Pose2D{1.3 + 1.5 * dt_s, 1.7, 0.4 + 2.0 * dt_s}; };
  const double readout_s = 0.025;
  renderer_.render_rolling(moving, readout_s, mount_, effects_, 3, &rolling_);
  const int h = options_.intrinsics.height;
  for (int row : {0, 57, 239, 240, 411, h - 1}) {
    renderer_.render(moving((row - 0.5 * (h - 1)) / h * readout_s), mount_, effects_, 3, &global_);
    EXPECT_TRUE(same_row(global_, rolling_, row)) << "row " << row;
  }
  renderer_.render(moving(0.0), mount_, effects_, 3, &global_);
  EXPECT_FALSE(same_row(global_, rolling_, 0)) << "the first row is 12.5 ms early";
}

TEST(RollingShutterScenarios, MovingSetsCarryTheirPathAndStillSetsDoNot) {
  const SceneOptions options;
  auto drive = make_scenario("drive", options, 3, 1);
  ASSERT_TRUE(drive.ok());
  const ScenarioFrame& f = drive->frames[2];
  ASSERT_NE(f.path, nullptr);
  const Pose2D at = scenario_pose_at(f, options.layout, 0.0);
  EXPECT_EQ(at.x_m, f.pose.x_m);
  EXPECT_EQ(at.yaw_rad, f.pose.yaw_rad);
  EXPECT_NE(scenario_pose_at(f, options.layout, 0.01).x_m, f.pose.x_m);
  auto random = make_scenario("random", options, 2, 1);
  ASSERT_TRUE(random.ok());
  EXPECT_EQ(random->frames[0].path, nullptr);
  EXPECT_EQ(scenario_pose_at(random->frames[0], options.layout, 0.01).x_m,
            random->frames[0].pose.x_m);
}

}  // namespace
}  // namespace ceilpose::sim
