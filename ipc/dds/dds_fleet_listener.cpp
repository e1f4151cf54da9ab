#include "ipc/dds/dds_fleet_listener.h"

#include <algorithm>
#include <array>
#include <cstring>

#include "core/clock.h"
#include "ipc/dds/dds_error.h"
#include "ipc/dds/dds_qos.h"
#include "ipc/dds/dds_topic_discovery.h"

namespace ceilpose {
namespace {

constexpr char kPoseTypeName[] = "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_";
constexpr size_t kTakeBatch = 16;

}  // namespace

Result<DdsFleetListener> DdsFleetListener::create(const DdsDomainOptions& options) {
  auto participant = DdsParticipant::create(options);
  if (!participant) return participant.error();
  DdsFleetListener l;
  l.participant_ = std::move(participant.value());
  const std::string domain = "DDS domain " + std::to_string(l.participant_.domain_id());
  l.waitset_ = dds_create_waitset(l.participant_.handle());
  if (l.waitset_ < 0) return dds_error("cannot create a waitset on " + domain, l.waitset_);
  auto discovery =
      DdsTopicDiscovery::create(l.participant_.handle(), l.waitset_, kPoseTypeName, "/pose");
  if (!discovery) return make_error(discovery.error().message + " on " + domain);
  l.discovery_ = std::move(discovery).value();
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
  std::vector<DiscoveredTopic> found;
  if (auto ok = discovery_.take_new(&found); !ok) return ok;
  for (DiscoveredTopic& t : found) {
    Entry entry;
    entry.robot.robot = t.robot;
    entry.robot.topic = t.topic;
    entry.robot.type_name = t.type_name;
    entry.robot.xcdr1 = t.xcdr1;
    // Keep the latest only: the listing shows where robots are.
    auto reader =
        create_fleet_reader(participant_.handle(), waitset_,
                            &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc, t.topic, 1);
    if (!reader) return reader.error();
    entry.reader = *reader;
    entries_.emplace(entry.robot.topic, std::move(entry));
  }
  return {};
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
