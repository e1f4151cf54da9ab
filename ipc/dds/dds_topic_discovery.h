#pragma once
// Finds every robot's topic of one type on a domain: reads the DCPSPublication
// built-in topic and reports each topic rt/<robot><suffix> of `type_name`
// once, the first time a writer of it is seen. `ceilposectl fleet` (poses)
// and the daemon's fleet (states) both discover robots this way, then make a
// reader per topic.
//
// Not thread-safe: one thread calls take_new().
#include <dds/dds.h>

#include <set>
#include <string>
#include <vector>

#include "core/result.h"

namespace ceilpose {

struct DiscoveredTopic {
  std::string robot;      // from the topic name
  std::string topic;      // DDS topic name
  std::string type_name;  // DDS type name the writer announced
  bool xcdr1 = true;      // the writer offers XCDR1 (or no data representation)
};

class DdsTopicDiscovery {
 public:
  DdsTopicDiscovery() = default;
  // The reader is a child of `participant` and is attached to `waitset`, so
  // waiting on it wakes for discovery too.
  static Result<DdsTopicDiscovery> create(dds_entity_t participant, dds_entity_t waitset,
                                          std::string type_name, std::string topic_suffix);

  // Appends topics seen for the first time to *found.
  Result<void> take_new(std::vector<DiscoveredTopic>* found);

 private:
  dds_entity_t reader_ = 0;  // child of the participant: deleted with it
  std::string type_name_;
  std::string suffix_;
  std::set<std::string> seen_;
};

// A best-effort reader of `topic` for the latest samples: `depth` kept per
// instance, accepting XCDR1 and XCDR2. Its data wakes
// `waitset`, or, given a `listener`, calls that listener instead (in DDS's
// receive thread, with no thread to wake). The error names the topic.
Result<dds_entity_t> create_fleet_reader(dds_entity_t participant, dds_entity_t waitset,
                                         const dds_topic_descriptor_t* descriptor,
                                         const std::string& topic, int32_t depth,
                                         const dds_listener_t* listener = nullptr);

}  // namespace ceilpose
