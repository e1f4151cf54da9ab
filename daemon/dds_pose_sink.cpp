#include "daemon/dds_pose_sink.h"

#include "core/clock.h"
#include "daemon/pose_record_of.h"
#include "ipc/dds/dds_pose_publisher.h"

namespace ceilpose::daemon {

void DdsPoseSink::consume(const Localization& loc) {
  // ROS consumers take any pose on the topic as a fix: invalid ones stay off it.
  if (!loc.published.valid) return;
  const PoseRecord record = pose_record_of(loc, realtime_ns() - monotonic_ns());
  DdsPose pose;
  pose.capture_realtime_ns = record.capture_real_ns;
  pose.valid = true;
  pose.pose = loc.published.pose;
  pose.covariance = loc.published.covariance;
  pose.has_velocity = loc.motion.valid;
  if (pose.has_velocity) {
    const MotionState& s = loc.motion.state;
    pose.velocity = {s.x[3], s.x[4], s.x[5]};
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        pose.velocity_covariance[r * 3 + c] = s.p[(3 + r) * kMotionStates + 3 + c];
  }
  if (!publisher_->publish(pose)) failures_.fetch_add(1, std::memory_order_relaxed);
  // The fleet's copy carries the pose sequence of this output, so that
  // receivers can count lost samples.
  PoseRecord state = record;
  state.seq = ++state_seq_;
  if (!publisher_->publish_state(state)) failures_.fetch_add(1, std::memory_order_relaxed);
}

void DdsPoseSink::publish_status(const ServiceStatus& s) {
  DdsStatus ds;
  ds.publish_realtime_ns = realtime_ns();
  ds.health = s.source_failed ? DdsHealth::kFailed
                              : (s.fix == FixState::kOk ? DdsHealth::kOk : DdsHealth::kDegraded);
  ds.fix = s.fix == FixState::kOk || s.fix == FixState::kCoasting;
  ds.mode = static_cast<uint8_t>(s.mode);
  ds.markers = static_cast<uint16_t>(s.markers);
  ds.fps = static_cast<float>(s.fps);
  ds.frames = s.capture.frames;
  ds.drops = s.capture.drops + s.capture.source_drops;
  ds.latency_p50_us = static_cast<uint32_t>(s.latency.p50_us);
  ds.latency_p90_us = static_cast<uint32_t>(s.latency.p90_us);
  ds.latency_p99_us = static_cast<uint32_t>(s.latency.p99_us);
  ds.latency_max_us = static_cast<uint32_t>(s.latency.max_us);
  ds.refusals = s.refusals;
  if (!publisher_->publish_status(ds)) failures_.fetch_add(1, std::memory_order_relaxed);
  if (auto others = publisher_->other_pose_writers(); others) {
    other_pose_writers_.store(*others, std::memory_order_relaxed);
  } else {
    failures_.fetch_add(1, std::memory_order_relaxed);
  }
}

}  // namespace ceilpose::daemon
