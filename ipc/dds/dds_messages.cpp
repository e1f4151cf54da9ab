#include "ipc/dds/dds_messages.h"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace ceilpose {
namespace {

constexpr int64_t kNsPerS = 1'000'000'000;

// ROS 2's Time is (int32 sec, uint32 nanosec) with nanosec in [0, 1e9):
// floor division keeps that true for times before the epoch too.
builtin_interfaces_msg_dds__Time_ to_time(int64_t realtime_ns) {
  int64_t sec = realtime_ns / kNsPerS;
  int64_t nsec = realtime_ns % kNsPerS;
  if (nsec < 0) {
    nsec += kNsPerS;
    sec -= 1;
  }
  return {static_cast<int32_t>(sec), static_cast<uint32_t>(nsec)};
}

int64_t from_time(const builtin_interfaces_msg_dds__Time_& t) {
  return int64_t{t.sec} * kNsPerS + t.nanosec;
}

// Row/column of x, y and rotation about z in ROS's 6x6 pose covariance
// (x, y, z, rot_x, rot_y, rot_z).
constexpr std::array<int, 3> kPlanarIndex{0, 1, 5};

}  // namespace

void to_message(const DdsPose& pose, geometry_msgs_msg_dds__PoseWithCovarianceStamped_* msg) {
  msg->header.stamp = to_time(pose.capture_realtime_ns);
  // Cyclone only reads the string during dds_write; the cast drops a const
  // the generated C struct cannot express.
  msg->header.frame_id = const_cast<char*>(kMapFrame);
  auto& p = msg->pose.pose;
  p.position.x = pose.pose.x_m;
  p.position.y = pose.pose.y_m;
  p.position.z = 0.0;
  // Rotation by yaw about +z: q = (0, 0, sin(yaw/2), cos(yaw/2)).
  p.orientation.x = 0.0;
  p.orientation.y = 0.0;
  p.orientation.z = std::sin(0.5 * pose.pose.yaw_rad);
  p.orientation.w = std::cos(0.5 * pose.pose.yaw_rad);
  // The 3x3 (x, y, yaw) block goes to rows/columns (0, 1, 5) of the 6x6;
  // z, roll and pitch are unobserved: large variance, no correlation.
  auto& c = msg->pose.covariance;
  for (double& v : c) v = 0.0;
  c[2 * 6 + 2] = kUnobservedVariance;
  c[3 * 6 + 3] = kUnobservedVariance;
  c[4 * 6 + 4] = kUnobservedVariance;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) {
      c[kPlanarIndex[r] * 6 + kPlanarIndex[k]] = pose.covariance[r * 3 + k];
    }
  }
}

void to_message(const DdsPose& pose, nav_msgs_msg_dds__Odometry_* msg) {
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ stamped;
  to_message(pose, &stamped);
  msg->header = stamped.header;
  msg->pose = stamped.pose;
  msg->child_frame_id = const_cast<char*>(kBaseFrame);
  auto& t = msg->twist;
  for (double& v : t.covariance) v = 0.0;
  t.twist.linear = {0.0, 0.0, 0.0};
  t.twist.angular = {0.0, 0.0, 0.0};
  if (!pose.has_velocity) {
    for (int i = 0; i < 6; ++i) t.covariance[i * 6 + i] = kUnobservedVariance;
    return;
  }
  // World to base_link: R(-yaw) on (vx, vy); the yaw rate is the same in both.
  const double c = std::cos(pose.pose.yaw_rad), s = std::sin(pose.pose.yaw_rad);
  const double r[3][3] = {{c, s, 0.0}, {-s, c, 0.0}, {0.0, 0.0, 1.0}};
  double body[3] = {};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) body[i] += r[i][k] * pose.velocity[k];
  t.twist.linear.x = body[0];
  t.twist.linear.y = body[1];
  t.twist.angular.z = body[2];
  // R Σ Rᵀ into rows/columns (vx, vy, rate about z) of the 6x6; vz, roll and
  // pitch rates are unobserved.
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double sum = 0.0;
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) sum += r[i][k] * pose.velocity_covariance[k * 3 + l] * r[j][l];
      t.covariance[kPlanarIndex[i] * 6 + kPlanarIndex[j]] = sum;
    }
  t.covariance[2 * 6 + 2] = kUnobservedVariance;
  t.covariance[3 * 6 + 3] = kUnobservedVariance;
  t.covariance[4 * 6 + 4] = kUnobservedVariance;
}

DdsPose from_message(const geometry_msgs_msg_dds__PoseWithCovarianceStamped_& msg) {
  DdsPose out;
  out.valid = true;
  out.capture_realtime_ns = from_time(msg.header.stamp);
  const auto& p = msg.pose.pose;
  out.pose.x_m = p.position.x;
  out.pose.y_m = p.position.y;
  const auto& q = p.orientation;
  // Yaw of a general quaternion (z-y-x Euler); equals 2*atan2(z, w) for a pure yaw.
  out.pose.yaw_rad = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) {
      out.covariance[r * 3 + k] = msg.pose.covariance[kPlanarIndex[r] * 6 + kPlanarIndex[k]];
    }
  }
  return out;
}

void to_message(const DdsStatus& status, const std::string& robot, ceilpose_msg_dds__Status_* msg) {
  msg->header.stamp = to_time(status.publish_realtime_ns);
  msg->header.frame_id = const_cast<char*>(kMapFrame);
  msg->robot = const_cast<char*>(robot.c_str());
  msg->health = static_cast<uint8_t>(status.health);
  msg->fix = status.fix;
  msg->mode = status.mode;
  msg->markers = status.markers;
  msg->fps = status.fps;
  msg->frames = status.frames;
  msg->drops = status.drops;
  msg->latency_p50_us = status.latency_p50_us;
  msg->latency_p90_us = status.latency_p90_us;
  msg->latency_p99_us = status.latency_p99_us;
  msg->latency_max_us = status.latency_max_us;
  constexpr size_t kSlots = sizeof(msg->refusals) / sizeof(msg->refusals[0]);
  static_assert(kRefusalCount <= kSlots, "ceilpose_status.idl has a slot for every refusal");
  for (size_t i = 0; i < kSlots; ++i)
    msg->refusals[i] = i < status.refusals.size() ? status.refusals[i] : 0;
}

void to_message(const DdsPose& pose, const char* parent, const char* child,
                geometry_msgs_msg_dds__TransformStamped_* storage,
                tf2_msgs_msg_dds__TFMessage_* msg) {
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ stamped;
  to_message(pose, &stamped);  // one place turns a pose into position + quaternion
  storage->header.stamp = stamped.header.stamp;
  storage->header.frame_id = const_cast<char*>(parent);
  storage->child_frame_id = const_cast<char*>(child);
  const auto& p = stamped.pose.pose;
  storage->transform.translation = {p.position.x, p.position.y, p.position.z};
  storage->transform.rotation = p.orientation;
  msg->transforms._maximum = 1;
  msg->transforms._length = 1;
  msg->transforms._buffer = storage;
  msg->transforms._release = false;
}

void to_message(const PoseRecord& pose, ceilpose_msg_dds__State_* msg) {
  msg->header.stamp = to_time(pose.capture_real_ns);
  msg->header.frame_id = const_cast<char*>(kMapFrame);
  msg->seq = pose.seq;
  msg->flags = pose.flags;
  msg->mode = pose.mode;
  msg->markers = pose.markers;
  msg->x = pose.x_m;
  msg->y = pose.y_m;
  msg->yaw = pose.yaw_rad;
  std::copy(std::begin(pose.covariance), std::end(pose.covariance), msg->covariance);
  msg->velocity[0] = pose.vx_mps;
  msg->velocity[1] = pose.vy_mps;
  msg->velocity[2] = pose.yaw_rate_radps;
  msg->acceleration[0] = pose.ax_mps2;
  msg->acceleration[1] = pose.ay_mps2;
  msg->acceleration[2] = pose.yaw_accel_radps2;
  std::copy(std::begin(pose.state_covariance), std::end(pose.state_covariance),
            msg->state_covariance);
  std::copy(std::begin(pose.jerk_density), std::end(pose.jerk_density), msg->jerk_density);
  msg->predict_horizon_ms = pose.predict_horizon_ms;
}

PoseRecord from_message(const ceilpose_msg_dds__State_& msg) {
  PoseRecord pose{};
  pose.capture_real_ns = from_time(msg.header.stamp);
  pose.seq = msg.seq;
  pose.flags = msg.flags;
  pose.mode = msg.mode;
  pose.markers = msg.markers;
  pose.x_m = msg.x;
  pose.y_m = msg.y;
  pose.yaw_rad = msg.yaw;
  std::copy(std::begin(msg.covariance), std::end(msg.covariance), pose.covariance);
  pose.vx_mps = msg.velocity[0];
  pose.vy_mps = msg.velocity[1];
  pose.yaw_rate_radps = msg.velocity[2];
  pose.ax_mps2 = msg.acceleration[0];
  pose.ay_mps2 = msg.acceleration[1];
  pose.yaw_accel_radps2 = msg.acceleration[2];
  std::copy(std::begin(msg.state_covariance), std::end(msg.state_covariance),
            pose.state_covariance);
  std::copy(std::begin(msg.jerk_density), std::end(msg.jerk_density), pose.jerk_density);
  pose.predict_horizon_ms = msg.predict_horizon_ms;
  return pose;
}

}  // namespace ceilpose
