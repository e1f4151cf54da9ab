#include "daemon/shm_pose_sink.h"

#include <algorithm>

#include "core/clock.h"

namespace ceilpose::daemon {

void ShmPoseSink::consume(const Localization& loc) {
  const PoseEstimate& out = loc.published;
  const int64_t real_minus_mono_ns = realtime_ns() - monotonic_ns();
  PoseRecord rec{};
  rec.capture_mono_ns = loc.frame.timestamp_ns;
  rec.capture_real_ns = loc.frame.timestamp_ns + real_minus_mono_ns;
  rec.x_m = out.pose.x_m;
  rec.y_m = out.pose.y_m;
  rec.yaw_rad = out.pose.yaw_rad;
  std::copy(out.covariance.begin(), out.covariance.end(), rec.covariance);
  rec.flags = (out.valid ? kPoseValid : 0u) | (loc.filtered ? kPoseFiltered : 0u) |
              (loc.coasting() ? kPoseCoasting : 0u);
  rec.mode = static_cast<uint8_t>(out.mode);
  rec.markers = static_cast<uint16_t>(out.markers);
  rec.refusal = static_cast<uint8_t>(out.refusal);
  set_pose_motion(&rec, loc.motion);
  writer_->publish(rec);
}

void ShmPoseSink::publish_status(const ServiceStatus& s) {
  StatusRecord status{};
  status.fps = s.fps;
  status.frames = s.capture.frames;
  status.drops = s.capture.drops + s.capture.source_drops;
  status.skipped = s.capture.skipped;
  status.outages = s.capture.outages;
  status.latency_p50_us = static_cast<uint32_t>(s.latency.p50_us);
  status.latency_p90_us = static_cast<uint32_t>(s.latency.p90_us);
  status.latency_p99_us = static_cast<uint32_t>(s.latency.p99_us);
  status.latency_max_us = static_cast<uint32_t>(s.latency.max_us);
  status.fix_state = static_cast<uint32_t>(s.fix);
  status.refusal_count = static_cast<uint32_t>(s.refusals.size());
  std::copy(s.refusals.begin(), s.refusals.end(), status.refusals);
  set_status_source(&status, s.source);
  writer_->update_status(status);
}

}  // namespace ceilpose::daemon
