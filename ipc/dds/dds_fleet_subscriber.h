#pragma once
// The daemon's ear on the fleet: discovers every other robot's
// rt/<robot>/ceilpose_state topic, reads it reliably, and hands each sample
// (and each robot whose writer left) to a FleetSampleSink. Runs on the fleet
// thread, on the publisher's participant (one participant per process is
// cheapest for discovery and is what the permissions name).
#include <dds/dds.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/result.h"
#include "ipc/dds/dds_topic_discovery.h"
#include "ipc/shm/pose_record.h"

namespace ceilpose {

struct FleetSample {
  const std::string* robot = nullptr;  // the topic's robot name; valid during the call
  uint64_t writer = 0;                 // the DDS publication handle of its writer
  bool alive = true;                   // false: the writer left or lost liveliness (no pose)
  PoseRecord pose{};                   // capture_real_ns as sent; capture_mono_ns 0
};

class FleetSampleSink {
 public:
  virtual ~FleetSampleSink() = default;
  virtual void on_sample(const FleetSample& sample) = 0;
  // A robot's topic that could not be read (access control, resources).
  virtual void on_problem(const std::string& message) = 0;
};

class DdsFleetSubscriber {
 public:
  // `own_robot`'s topic is not read. `depth`: samples kept per robot between
  // polls (reliable QoS: a slow poll loses none of the last `depth`).
  static Result<DdsFleetSubscriber> create(dds_entity_t participant, std::string own_robot,
                                           int32_t depth);

  DdsFleetSubscriber(DdsFleetSubscriber&& other) noexcept;
  DdsFleetSubscriber& operator=(DdsFleetSubscriber&&) = delete;
  DdsFleetSubscriber(const DdsFleetSubscriber&) = delete;
  ~DdsFleetSubscriber();

  // Waits up to timeout_ms for discovery or data, then hands all of it to
  // `sink`. Allocates only when a new robot is discovered.
  Result<void> poll(int64_t timeout_ms, FleetSampleSink* sink);
  size_t topics() const { return readers_.size(); }

 private:
  DdsFleetSubscriber() = default;
  Result<void> take(const std::string& robot, dds_entity_t reader, FleetSampleSink* sink);

  dds_entity_t participant_ = 0;
  dds_entity_t waitset_ = 0;
  DdsTopicDiscovery discovery_;
  std::string own_robot_;
  int32_t depth_ = 8;
  std::map<std::string, dds_entity_t> readers_;  // by robot name
  std::vector<DiscoveredTopic> found_;           // reused between polls
};

}  // namespace ceilpose
