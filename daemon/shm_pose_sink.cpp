#include "daemon/shm_pose_sink.h"

#include <algorithm>

#include "core/clock.h"
#include "daemon/pose_record_of.h"

namespace ceilpose::daemon {

void ShmPoseSink::consume(const Localization& loc) {
  writer_->publish(pose_record_of(loc, realtime_ns() - monotonic_ns()));
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
  // Modulo 2^32 (the ABI's reserved words): readers take differences.
  status.tracked_frames = static_cast<uint32_t>(s.sweeps.tracked());
  status.full_sweep_frames = static_cast<uint32_t>(s.sweeps.full());
  std::copy(s.refusals.begin(), s.refusals.end(), status.refusals);
  set_status_source(&status, s.source);
  writer_->update_status(status);
}

}  // namespace ceilpose::daemon
