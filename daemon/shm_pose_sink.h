#pragma once
// Shared memory output of ceilposed: every frame's published pose (valid or
// not, so readers see the daemon live without a fix) and the status block.
#include "daemon/publishing_sink.h"
#include "ipc/shm/shm_pose_writer.h"

namespace ceilpose::daemon {

class ShmPoseSink final : public PublishingSink {
 public:
  ShmPoseSink(ShmPoseWriter* writer, int status_interval_ms)
      : writer_(writer), status_period_ns_(int64_t{status_interval_ms} * 1'000'000) {}

  void consume(const Localization& localization) override;
  void publish_status(const ServiceStatus& status) override;
  int64_t status_period_ns() const override { return status_period_ns_; }

 private:
  ShmPoseWriter* writer_;
  int64_t status_period_ns_;
};

}  // namespace ceilpose::daemon
