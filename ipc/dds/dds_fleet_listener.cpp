#include "ipc/dds/dds_fleet_listener.h"

#include <algorithm>
#include <array>
#include <cstring>

#include "core/clock.h"
#include "ipc/dds/dds_error.h"
#include "ipc/dds/dds_qos.h"

namespace ceilpose {
namespace {

constexpr char kPoseTypeName[] = "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_";
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

Result<DdsFleetListener> DdsFleetListener::create(const DdsDomainOptions& options) {
  auto participant = DdsParticipant::create(options);
  if (!participant) return participant.error();
  DdsFleetListener l;
  l.participant_ = std::move(participant.value());
  const std::string domain = "DDS domain " + std::to_string(l.participant_.domain_id());

  l.publication_reader_ = dds_create_reader(l.participant_.handle(),
                                            DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  if (l.publication_reader_ < 0) {
    return dds_error("cannot read DCPSPublication on " + domain, l.publication_reader_);
  }
  l.waitset_ = dds_create_waitset(l.participant_.handle());
  if (l.waitset_ < 0) return dds_error("cannot create a waitset on " + domain, l.waitset_);
  if (const dds_return_t rc = dds_set_status_mask(l.publication_reader_, DDS_DATA_AVAILABLE_STATUS);
      rc != DDS_RETCODE_OK) {
    return dds_error("cannot watch DCPSPublication on " + domain, rc);
  }
  if (const dds_return_t rc = dds_waitset_attach(l.waitset_, l.publication_reader_, 0);
      rc != DDS_RETCODE_OK) {
    return dds_error("cannot attach the DCPSPublication reader on " + domain, rc);
  }
  return l;
}

Result<void> DdsFleetListener::poll(int64_t timeout_ms) {
  const dds_return_t rc = dds_waitset_wait(waitset_, nullptr, 0, DDS_MSECS(timeout_ms));
  if (rc < 0) {
    return dds_error("waiting on DDS domain " + std::to_string(domain_id()) + " failed", rc);
  }
  if (auto ok = take_publications(); !ok) return ok;
  for (auto& [topic, entry] : entries_) {
    if (auto ok = take_poses(&entry.robot, entry.reader); !ok) return ok;
  }
  return {};
}

Result<void> DdsFleetListener::listen_for(int64_t duration_ms) {
  const int64_t deadline_ns = monotonic_ns() + duration_ms * 1'000'000;
  for (int64_t now = monotonic_ns(); now < deadline_ns; now = monotonic_ns()) {
    const int64_t left_ms = std::max<int64_t>(1, (deadline_ns - now + 999'999) / 1'000'000);
    if (auto ok = poll(left_ms); !ok) return ok;
  }
  return {};
}

Result<void> DdsFleetListener::take_publications() {
  std::array<void*, kTakeBatch> samples{};
  std::array<dds_sample_info_t, kTakeBatch> infos{};
  for (;;) {
    samples.fill(nullptr);  // null entries ask Cyclone to lend its own buffers
    const dds_return_t n =
        dds_take(publication_reader_, samples.data(), infos.data(), kTakeBatch, kTakeBatch);
    if (n < 0) return dds_error("cannot take DCPSPublication samples", n);
    if (n == 0) return {};
    Result<void> result;
    for (dds_return_t k = 0; k < n && result.ok(); ++k) {
      if (!infos[k].valid_data) continue;
      const auto* pub = static_cast<const dds_builtintopic_endpoint_t*>(samples[k]);
      if (pub->type_name == nullptr || std::strcmp(pub->type_name, kPoseTypeName) != 0) continue;
      const std::string robot = robot_from_pose_topic(pub->topic_name);
      if (robot.empty() || entries_.contains(pub->topic_name)) continue;

      Entry entry;
      entry.robot.robot = robot;
      entry.robot.topic = pub->topic_name;
      entry.robot.type_name = pub->type_name;
      entry.robot.xcdr1 = offers_xcdr1(pub->qos);
      const dds_entity_t topic = dds_create_topic(
          participant_.handle(), &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc,
          pub->topic_name, nullptr, nullptr);
      if (topic < 0) {
        result = dds_error(std::string("cannot create DDS topic ") + pub->topic_name, topic);
        break;
      }
      // Best-effort readers match reliable and best-effort writers alike;
      // only the latest pose matters. Accept both encodings.
      DdsQos qos = make_dds_qos();
      dds_qset_reliability(qos.get(), DDS_RELIABILITY_BEST_EFFORT, 0);
      dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 1);
      const std::array<dds_data_representation_id_t, 2> representations{
          DDS_DATA_REPRESENTATION_XCDR1, DDS_DATA_REPRESENTATION_XCDR2};
      dds_qset_data_representation(qos.get(), representations.size(), representations.data());
      entry.reader = dds_create_reader(participant_.handle(), topic, qos.get(), nullptr);
      if (entry.reader < 0) {
        result =
            dds_error(std::string("cannot create a reader for ") + pub->topic_name, entry.reader);
        break;
      }
      dds_return_t rc = dds_set_status_mask(entry.reader, DDS_DATA_AVAILABLE_STATUS);
      if (rc == DDS_RETCODE_OK) rc = dds_waitset_attach(waitset_, entry.reader, 0);
      if (rc != DDS_RETCODE_OK) {
        result = dds_error(std::string("cannot wait for data on ") + pub->topic_name, rc);
        break;
      }
      entries_.emplace(entry.robot.topic, std::move(entry));
    }
    if (const dds_return_t rc = dds_return_loan(publication_reader_, samples.data(), n);
        rc != DDS_RETCODE_OK && result.ok()) {
      result = dds_error("cannot return DCPSPublication samples", rc);
    }
    if (!result) return result;
  }
}

Result<void> DdsFleetListener::take_poses(FleetRobot* robot, dds_entity_t reader) {
  std::array<void*, kTakeBatch> samples{};
  std::array<dds_sample_info_t, kTakeBatch> infos{};
  for (;;) {
    samples.fill(nullptr);
    const dds_return_t n = dds_take(reader, samples.data(), infos.data(), kTakeBatch, kTakeBatch);
    if (n < 0) return dds_error("cannot take samples of " + robot->topic, n);
    if (n == 0) return {};
    const int64_t now_ns = monotonic_ns();
    for (dds_return_t k = 0; k < n; ++k) {
      if (!infos[k].valid_data) continue;
      robot->latest = from_message(
          *static_cast<const geometry_msgs_msg_dds__PoseWithCovarianceStamped_*>(samples[k]));
      robot->received_monotonic_ns = now_ns;
      ++robot->samples;
    }
    if (const dds_return_t rc = dds_return_loan(reader, samples.data(), n); rc != DDS_RETCODE_OK) {
      return dds_error("cannot return samples of " + robot->topic, rc);
    }
  }
}

std::vector<FleetRobot> DdsFleetListener::robots() const {
  std::vector<FleetRobot> out;
  out.reserve(entries_.size());
  for (const auto& [topic, entry] : entries_) out.push_back(entry.robot);
  std::sort(out.begin(), out.end(),
            [](const FleetRobot& a, const FleetRobot& b) { return a.robot < b.robot; });
  return out;
}

}  // namespace ceilpose
