#pragma once
// Listens to every robot's pose on a DDS domain: discovers writers of
// geometry_msgs::msg::dds_::PoseWithCovarianceStamped_ on topics
// rt/<robot>/pose through the DCPSPublication built-in topic, creates a
// reader per topic and keeps each robot's latest pose with its receive time.
//
// Not thread-safe: one thread calls poll()/listen_for() and robots().
#include <dds/dds.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/result.h"
#include "ipc/dds/dds_messages.h"
#include "ipc/dds/dds_options.h"
#include "ipc/dds/dds_participant.h"
#include "ipc/dds/dds_topic_discovery.h"

namespace ceilpose {

struct FleetRobot {
  std::string robot;      // from the topic name rt/<robot>/pose
  std::string topic;      // DDS topic name
  std::string type_name;  // DDS type name the writer announced
  bool xcdr1 = true;      // the writer announced XCDR1 (or no data representation)
  DdsPose latest;         // valid only once samples > 0
  int64_t received_monotonic_ns = 0;
  uint64_t samples = 0;
};

class DdsFleetListener {
 public:
  static Result<DdsFleetListener> create(const DdsDomainOptions& options);

  DdsFleetListener(DdsFleetListener&&) noexcept = default;
  DdsFleetListener& operator=(DdsFleetListener&&) noexcept = default;

  // Waits up to timeout_ms for discovery or data, then handles all of it.
  Result<void> poll(int64_t timeout_ms);
  // Keeps polling until duration_ms have passed.
  Result<void> listen_for(int64_t duration_ms);

  // Every pose topic discovered, sorted by robot name, with or without samples.
  std::vector<FleetRobot> robots() const;
  uint32_t domain_id() const { return participant_.domain_id(); }

 private:
  DdsFleetListener() = default;
  Result<void> take_publications();
  Result<void> take_poses(FleetRobot* robot, dds_entity_t reader);

  struct Entry {
    FleetRobot robot;
    dds_entity_t reader = 0;
  };

  DdsParticipant participant_;  // parent of every entity below
  DdsTopicDiscovery discovery_;
  dds_entity_t waitset_ = 0;
  std::map<std::string, Entry> entries_;  // by DDS topic name
};

}  // namespace ceilpose
