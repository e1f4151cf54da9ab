#pragma once
// DDS output of ceilposed: valid poses on rt/<robot>/pose (with odometry on
// rt/<robot>/odom and the full state for the fleet on
// rt/<robot>/ceilpose_state), the health on
// rt/<robot>/ceilpose_status every dds.status_period_ms. A failed write is
// counted, never logged from the pipeline thread.
#include <atomic>

#include "daemon/publishing_sink.h"

namespace ceilpose {
class DdsPosePublisher;
}

namespace ceilpose::daemon {

class DdsPoseSink final : public PublishingSink {
 public:
  DdsPoseSink(DdsPosePublisher* publisher, int status_period_ms)
      : publisher_(publisher), status_period_ns_(int64_t{status_period_ms} * 1'000'000) {}

  void consume(const Localization& localization) override;
  void publish_status(const ServiceStatus& status) override;
  int64_t status_period_ns() const override { return status_period_ns_; }
  uint64_t failures() const override { return failures_.load(std::memory_order_relaxed); }
  // Other processes' writers on this robot's pose topic, as of the last
  // status (the control thread warns; see DdsPosePublisher).
  size_t other_pose_writers() const { return other_pose_writers_.load(std::memory_order_relaxed); }

 private:
  DdsPosePublisher* publisher_;
  int64_t status_period_ns_;
  uint64_t state_seq_ = 0;  // pipeline thread only
  std::atomic<uint64_t> failures_{0};
  std::atomic<size_t> other_pose_writers_{0};
};

}  // namespace ceilpose::daemon
