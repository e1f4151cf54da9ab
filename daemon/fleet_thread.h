#pragma once
// The daemon's fleet: a thread of normal priority that listens to the other
// robots' states on DDS (DdsFleetSubscriber), lets the FleetKeeper decide
// what reaches <shm>-fleet, ages robots out and keeps the segment's
// heartbeat. It shares the publisher's DDS participant and must stop before
// that participant goes.
#include <dds/dds.h>

#include <atomic>
#include <memory>
#include <optional>
#include <thread>

#include "core/result.h"
#include "ipc/dds/dds_fleet_subscriber.h"
#include "ipc/fleet/fleet_keeper.h"
#include "ipc/shm/shm_fleet_writer.h"

namespace ceilpose::daemon {

class FleetThread {
 public:
  // Creates the segment fleet_segment_name(shm_name) and the subscriber on
  // `participant`; the thread starts in start().
  static Result<std::unique_ptr<FleetThread>> create(
      const FleetOptions& options, const std::string& shm_name, const std::string& group,
      dds_entity_t participant, const std::string& own_robot, shm::ShmErrc* code);
  ~FleetThread();

  void start();
  // Idempotent; marks the segment stopped.
  void stop();
  const std::string& segment_name() const { return writer_.name(); }
  // What other processes did to the segment; the writer repaired it. Any thread.
  shm::SegmentDamage damage() const { return {writer_.truncations(), writer_.header_repairs()}; }
  uint32_t robots() const { return writer_.robots(); }

 private:
  FleetThread(ShmFleetWriter writer, DdsFleetSubscriber subscriber, const FleetOptions& options);
  void run();

  ShmFleetWriter writer_;
  DdsFleetSubscriber subscriber_;
  FleetKeeper keeper_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace ceilpose::daemon
