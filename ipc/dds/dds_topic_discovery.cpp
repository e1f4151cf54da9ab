#include "ipc/dds/dds_topic_discovery.h"

#include <array>
#include <cstring>

#include "ipc/dds/dds_error.h"
#include "ipc/dds/dds_options.h"
#include "ipc/dds/dds_qos.h"

namespace ceilpose {
namespace {

constexpr size_t kTakeBatch = 16;

// True when the writer's QoS offers XCDR1 first, or no data representation
// at all (which DDS-XTypes defines as XCDR1).
bool offers_xcdr1(const dds_qos_t* qos) {
  uint32_t n = 0;
  dds_data_representation_id_t* values = nullptr;
  if (qos == nullptr || !dds_qget_data_representation(qos, &n, &values)) return true;
  const bool xcdr1 = n == 0 || values[0] == DDS_DATA_REPRESENTATION_XCDR1;
  dds_free(values);
  return xcdr1;
}

}  // namespace

Result<DdsTopicDiscovery> DdsTopicDiscovery::create(dds_entity_t participant, dds_entity_t waitset,
                                                    std::string type_name,
                                                    std::string topic_suffix) {
  DdsTopicDiscovery d;
  d.type_name_ = std::move(type_name);
  d.suffix_ = std::move(topic_suffix);
  d.reader_ = dds_create_reader(participant, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  if (d.reader_ < 0) return dds_error("cannot read DCPSPublication", d.reader_);
  if (const dds_return_t rc = dds_set_status_mask(d.reader_, DDS_DATA_AVAILABLE_STATUS);
      rc != DDS_RETCODE_OK) {
    return dds_error("cannot watch DCPSPublication", rc);
  }
  if (const dds_return_t rc = dds_waitset_attach(waitset, d.reader_, 0); rc != DDS_RETCODE_OK) {
    return dds_error("cannot attach the DCPSPublication reader to a waitset", rc);
  }
  return d;
}

Result<void> DdsTopicDiscovery::take_new(std::vector<DiscoveredTopic>* found) {
  std::array<void*, kTakeBatch> samples{};
  std::array<dds_sample_info_t, kTakeBatch> infos{};
  for (;;) {
    samples.fill(nullptr);  // null entries ask Cyclone to lend its own buffers
    const dds_return_t n = dds_take(reader_, samples.data(), infos.data(), kTakeBatch, kTakeBatch);
    if (n < 0) return dds_error("cannot take DCPSPublication samples", n);
    if (n == 0) return {};
    for (dds_return_t k = 0; k < n; ++k) {
      if (!infos[k].valid_data) continue;
      const auto* pub = static_cast<const dds_builtintopic_endpoint_t*>(samples[k]);
      if (pub->type_name == nullptr || pub->topic_name == nullptr || type_name_ != pub->type_name ||
          seen_.contains(pub->topic_name)) {
        continue;
      }
      std::string robot = robot_from_topic(pub->topic_name, suffix_);
      if (robot.empty()) continue;
      seen_.insert(pub->topic_name);
      found->push_back({std::move(robot), pub->topic_name, pub->type_name, offers_xcdr1(pub->qos)});
    }
    if (const dds_return_t rc = dds_return_loan(reader_, samples.data(), n); rc != DDS_RETCODE_OK) {
      return dds_error("cannot return DCPSPublication samples", rc);
    }
  }
}

Result<dds_entity_t> create_fleet_reader(dds_entity_t participant, dds_entity_t waitset,
                                         const dds_topic_descriptor_t* descriptor,
                                         const std::string& topic, int32_t depth,
                                         const dds_listener_t* listener) {
  const dds_entity_t t = dds_create_topic(participant, descriptor, topic.c_str(), nullptr, nullptr);
  if (t < 0) return dds_error("cannot create DDS topic " + topic, t);
  DdsQos qos = make_dds_qos();
  // Best effort: only the latest pose matters, and a retransmitted one would
  // arrive behind the next sample (33 ms later) and hold it up. A best-effort
  // reader matches reliable and best-effort writers alike, and sends no
  // acknowledgements: part of what brought the observer of 50 secure robots
  // under 10 % of a core (docs/fleet.md, session 22).
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, depth);
  const std::array<dds_data_representation_id_t, 2> representations{DDS_DATA_REPRESENTATION_XCDR1,
                                                                    DDS_DATA_REPRESENTATION_XCDR2};
  dds_qset_data_representation(qos.get(), representations.size(), representations.data());
  const dds_entity_t reader = dds_create_reader(participant, t, qos.get(), listener);
  if (reader < 0) return dds_error("cannot create a reader for " + topic, reader);
  if (listener != nullptr) return reader;
  dds_return_t rc = dds_set_status_mask(reader, DDS_DATA_AVAILABLE_STATUS);
  if (rc == DDS_RETCODE_OK) rc = dds_waitset_attach(waitset, reader, 0);
  if (rc != DDS_RETCODE_OK) return dds_error("cannot wait for data on " + topic, rc);
  return reader;
}

}  // namespace ceilpose
