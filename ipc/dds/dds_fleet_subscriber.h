#pragma once
// The daemon's ear on the fleet: discovers every other robot's
// rt/<robot>/ceilpose_state topic, reads it reliably, and hands each sample
// (and each robot whose writer left) to a FleetSampleSink. Discovery runs on
// the fleet thread (poll); samples are taken by a listener in DDS's receive
// thread the moment they arrive, so a sample costs no thread wake-up (with
// 50 robots at 30 Hz the wake-ups were most of the observer's CPU). On the
// publisher's participant (one participant per process is cheapest for
// discovery and is what the permissions name).
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

// Called from DDS's receive threads (more than one: unicast, multicast)
// and from the thread calling poll(): the sink serialises itself.
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

  // Waits up to timeout_ms for a robot to be discovered and makes its
  // reader, whose samples then go to `sink` (which must outlive
  // stop_listening()). Allocates only when a new robot is discovered.
  Result<void> poll(int64_t timeout_ms, FleetSampleSink* sink);
  // Deletes the readers; returns once no listener runs any more. Idempotent.
  void stop_listening();
  size_t topics() const { return readers_.size(); }

 private:
  // A listener's argument: lives in readers_, whose nodes never move.
  struct Reader {
    const std::string* robot = nullptr;
    FleetSampleSink* sink = nullptr;
    dds_entity_t handle = 0;
  };
  DdsFleetSubscriber() = default;
  static void on_data_available(dds_entity_t reader, void* arg);
  static Result<void> take(const std::string& robot, dds_entity_t reader, FleetSampleSink* sink);

  dds_entity_t participant_ = 0;
  dds_entity_t waitset_ = 0;
  DdsTopicDiscovery discovery_;
  std::string own_robot_;
  int32_t depth_ = 8;
  std::map<std::string, Reader> readers_;  // by robot name
  std::vector<DiscoveredTopic> found_;     // reused between polls
};

}  // namespace ceilpose
