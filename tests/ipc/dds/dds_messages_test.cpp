#include "ipc/dds/dds_messages.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

namespace ceilpose {
namespace {

DdsPose sample_pose() {
  DdsPose p;
  p.valid = true;
  p.capture_realtime_ns = 1'700'000'123'456'789'012;
  p.pose = {1.5, -2.25, 0.75};
  p.covariance = {0.01, 0.002, 0.003, 0.002, 0.02, 0.004, 0.003, 0.004, 0.05};
  return p;
}

TEST(DdsMessages, StampIsCaptureTimeSplitIntoSecAndNanosec) {
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg{};
  to_message(sample_pose(), &msg);
  EXPECT_EQ(msg.header.stamp.sec, 1'700'000'123);
  EXPECT_EQ(msg.header.stamp.nanosec, 456'789'012u);
}

TEST(DdsMessages, StampBeforeEpochKeepsNanosecInRange) {
  DdsPose p = sample_pose();
  p.capture_realtime_ns = -1;
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg{};
  to_message(p, &msg);
  EXPECT_EQ(msg.header.stamp.sec, -1);
  EXPECT_EQ(msg.header.stamp.nanosec, 999'999'999u);
}

TEST(DdsMessages, FrameIsMap) {
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg{};
  to_message(sample_pose(), &msg);
  EXPECT_STREQ(msg.header.frame_id, "map");
}

TEST(DdsMessages, PositionIsOnTheFloor) {
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg{};
  to_message(sample_pose(), &msg);
  EXPECT_DOUBLE_EQ(msg.pose.pose.position.x, 1.5);
  EXPECT_DOUBLE_EQ(msg.pose.pose.position.y, -2.25);
  EXPECT_DOUBLE_EQ(msg.pose.pose.position.z, 0.0);
}

TEST(DdsMessages, OrientationIsYawAboutZ) {
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg{};
  to_message(sample_pose(), &msg);
  const auto& q = msg.pose.pose.orientation;
  EXPECT_DOUBLE_EQ(q.x, 0.0);
  EXPECT_DOUBLE_EQ(q.y, 0.0);
  EXPECT_DOUBLE_EQ(q.z, std::sin(0.375));
  EXPECT_DOUBLE_EQ(q.w, std::cos(0.375));
}

TEST(DdsMessages, CovarianceBlockGoesToXYAndRotZ) {
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg{};
  to_message(sample_pose(), &msg);
  const double* c = msg.pose.covariance;
  EXPECT_DOUBLE_EQ(c[0 * 6 + 0], 0.01);
  EXPECT_DOUBLE_EQ(c[0 * 6 + 1], 0.002);
  EXPECT_DOUBLE_EQ(c[0 * 6 + 5], 0.003);
  EXPECT_DOUBLE_EQ(c[1 * 6 + 1], 0.02);
  EXPECT_DOUBLE_EQ(c[1 * 6 + 5], 0.004);
  EXPECT_DOUBLE_EQ(c[5 * 6 + 0], 0.003);
  EXPECT_DOUBLE_EQ(c[5 * 6 + 1], 0.004);
  EXPECT_DOUBLE_EQ(c[5 * 6 + 5], 0.05);
}

TEST(DdsMessages, UnobservedAxesGetLargeUncorrelatedVariance) {
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg{};
  to_message(sample_pose(), &msg);
  const double* c = msg.pose.covariance;
  for (int k : {2, 3, 4}) {
    EXPECT_DOUBLE_EQ(c[k * 6 + k], kUnobservedVariance) << "axis " << k;
    for (int j = 0; j < 6; ++j) {
      if (j != k) {
        EXPECT_DOUBLE_EQ(c[k * 6 + j], 0.0) << k << "," << j;
      }
    }
  }
}

TEST(DdsMessages, FromMessageInvertsToMessage) {
  const DdsPose in = sample_pose();
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg{};
  to_message(in, &msg);
  const DdsPose out = from_message(msg);
  EXPECT_EQ(out.capture_realtime_ns, in.capture_realtime_ns);
  EXPECT_DOUBLE_EQ(out.pose.x_m, in.pose.x_m);
  EXPECT_DOUBLE_EQ(out.pose.y_m, in.pose.y_m);
  EXPECT_NEAR(out.pose.yaw_rad, in.pose.yaw_rad, 1e-12);
  for (int k = 0; k < 9; ++k) EXPECT_DOUBLE_EQ(out.covariance[k], in.covariance[k]) << k;
}

TEST(DdsMessages, YawNearPiSurvivesTheRoundTrip) {
  DdsPose in = sample_pose();
  in.pose.yaw_rad = std::numbers::pi - 1e-6;
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg{};
  to_message(in, &msg);
  EXPECT_NEAR(from_message(msg).pose.yaw_rad, in.pose.yaw_rad, 1e-9);
}

TEST(DdsMessages, OdometryWithoutVelocityMarksTheTwistUnknown) {
  DdsPose pose;
  pose.valid = true;
  pose.pose = {1.0, 2.0, 0.3};
  nav_msgs_msg_dds__Odometry_ msg;
  to_message(pose, &msg);
  EXPECT_STREQ(msg.header.frame_id, "map");
  EXPECT_STREQ(msg.child_frame_id, "base_link");
  EXPECT_EQ(msg.pose.pose.position.x, 1.0);
  EXPECT_EQ(msg.twist.twist.linear.x, 0.0);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(msg.twist.covariance[i * 6 + i], kUnobservedVariance);
}

TEST(DdsMessages, OdometryTwistIsInTheRobotsFrame) {
  DdsPose pose;
  pose.valid = true;
  pose.pose = {0.0, 0.0, std::numbers::pi / 2};  // facing North
  pose.has_velocity = true;
  pose.velocity = {0.0, 1.5, -0.2};  // driving North, turning right
  pose.velocity_covariance = {1e-4, 0.0, 0.0, 0.0, 4e-4, 0.0, 0.0, 0.0, 1e-3};
  nav_msgs_msg_dds__Odometry_ msg;
  to_message(pose, &msg);
  EXPECT_NEAR(msg.twist.twist.linear.x, 1.5, 1e-12) << "straight ahead";
  EXPECT_NEAR(msg.twist.twist.linear.y, 0.0, 1e-12);
  EXPECT_EQ(msg.twist.twist.angular.z, -0.2);
  // North's variance is now the forward one.
  EXPECT_NEAR(msg.twist.covariance[0], 4e-4, 1e-15);
  EXPECT_NEAR(msg.twist.covariance[7], 1e-4, 1e-15);
  EXPECT_EQ(msg.twist.covariance[35], 1e-3);
}

TEST(DdsMessages, StatusCarriesRobotAndFigures) {
  DdsStatus s;
  s.publish_realtime_ns = 2'000'000'001;
  s.health = DdsHealth::kDegraded;
  s.fix = false;
  s.fps = 29.5f;
  s.drops = 3;
  s.latency_p99_us = 812;
  const std::string robot = "alpha";
  ceilpose_msg_dds__Status_ msg{};
  to_message(s, robot, &msg);
  EXPECT_STREQ(msg.robot, "alpha");
  EXPECT_EQ(msg.header.stamp.sec, 2);
  EXPECT_EQ(msg.header.stamp.nanosec, 1u);
  EXPECT_EQ(msg.health, 1);
  EXPECT_FALSE(msg.fix);
  EXPECT_FLOAT_EQ(msg.fps, 29.5f);
  EXPECT_EQ(msg.drops, 3u);
  EXPECT_EQ(msg.latency_p99_us, 812u);
}

}  // namespace
}  // namespace ceilpose
