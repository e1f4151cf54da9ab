#pragma once
// The daemon's fleet: the other robots' states on DDS (DdsFleetSubscriber)
// go to the FleetKeeper, which decides what reaches <shm>-fleet, as they
// arrive (in DDS's receive threads); a thread of normal priority discovers
// robots, ages them out and keeps the segment's heartbeat. One mutex
// serialises the keeper and the writer between them. It shares the
// publisher's DDS participant and must stop before that participant goes.
#include <dds/dds.h>

#include <atomic>
#include <memory>
#include <mutex>
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

  // The keeper as DDS's receive threads see it: under mutex_.
  class LockedKeeper final : public FleetSampleSink {
   public:
    LockedKeeper(FleetKeeper* keeper, std::mutex* mutex) : keeper_(keeper), mutex_(mutex) {}
    void on_sample(const FleetSample& sample) override;
    void on_problem(const std::string& message) override;

   private:
    FleetKeeper* keeper_;
    std::mutex* mutex_;
  };

  ShmFleetWriter writer_;
  DdsFleetSubscriber subscriber_;
  std::mutex mutex_;  // the keeper and the writer's header
  FleetKeeper keeper_;
  LockedKeeper locked_keeper_{&keeper_, &mutex_};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace ceilpose::daemon
