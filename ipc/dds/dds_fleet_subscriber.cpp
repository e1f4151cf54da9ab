#include "ipc/dds/dds_fleet_subscriber.h"

#include <array>
#include <memory>
#include <utility>

#include "ipc/dds/dds_error.h"
#include "ipc/dds/dds_messages.h"

namespace ceilpose {
namespace {

constexpr char kStateTypeName[] = "ceilpose::msg::dds_::State_";
constexpr size_t kTakeBatch = 16;

}  // namespace

Result<DdsFleetSubscriber> DdsFleetSubscriber::create(dds_entity_t participant,
                                                      std::string own_robot, int32_t depth) {
  DdsFleetSubscriber s;
  s.participant_ = participant;
  s.own_robot_ = std::move(own_robot);
  s.depth_ = depth;
  s.waitset_ = dds_create_waitset(participant);
  if (s.waitset_ < 0) return dds_error("fleet: cannot create a waitset", s.waitset_);
  auto discovery =
      DdsTopicDiscovery::create(participant, s.waitset_, kStateTypeName, "/ceilpose_state");
  if (!discovery) return make_error("fleet: " + discovery.error().message);
  s.discovery_ = std::move(discovery).value();
  return s;
}

DdsFleetSubscriber::DdsFleetSubscriber(DdsFleetSubscriber&& other) noexcept
    : participant_(std::exchange(other.participant_, 0)),
      waitset_(std::exchange(other.waitset_, 0)),
      discovery_(std::move(other.discovery_)),
      own_robot_(std::move(other.own_robot_)),
      depth_(other.depth_),
      readers_(std::move(other.readers_)),
      found_(std::move(other.found_)) {}

DdsFleetSubscriber::~DdsFleetSubscriber() {
  // The listeners point into readers_: they stop before it goes. The
  // discovery reader goes with the participant; the waitset is ours to
  // delete while the participant lives.
  stop_listening();
  if (waitset_ > 0) dds_delete(waitset_);
}

void DdsFleetSubscriber::stop_listening() {
  // Deleting a reader waits for its listener calls in progress and makes no
  // new ones (Cyclone's entity deletion).
  for (auto& [robot, reader] : readers_) {
    if (reader.handle > 0) dds_delete(reader.handle);
  }
  readers_.clear();
}

void DdsFleetSubscriber::on_data_available(dds_entity_t reader, void* arg) {
  const auto* r = static_cast<const Reader*>(arg);
  if (auto ok = take(*r->robot, reader, r->sink); !ok) r->sink->on_problem(ok.error().message);
}

Result<void> DdsFleetSubscriber::poll(int64_t timeout_ms, FleetSampleSink* sink) {
  const dds_return_t rc = dds_waitset_wait(waitset_, nullptr, 0, DDS_MSECS(timeout_ms));
  if (rc < 0) return dds_error("fleet: waiting for DDS data failed", rc);
  if (rc == 0) return {};
  found_.clear();
  if (auto ok = discovery_.take_new(&found_); !ok) return ok;
  for (const DiscoveredTopic& t : found_) {
    if (t.robot == own_robot_ || readers_.contains(t.robot)) continue;
    const auto it = readers_.try_emplace(t.robot).first;
    Reader& entry = it->second;
    entry.robot = &it->first;
    entry.sink = sink;
    const std::unique_ptr<dds_listener_t, decltype(&dds_delete_listener)> listener(
        dds_create_listener(&entry), &dds_delete_listener);
    dds_lset_data_available(listener.get(), &DdsFleetSubscriber::on_data_available);
    auto reader = create_fleet_reader(participant_, waitset_, &ceilpose_msg_dds__State__desc,
                                      t.topic, depth_, listener.get());
    if (!reader) {
      readers_.erase(it);
      // Under DDS Security, access control refuses a reader the permissions
      // do not grant; enclaves made before the fleet existed lack it.
      sink->on_problem(reader.error().message +
                       " (with DDS Security the enclave's permissions must allow subscribing to "
                       "rt/*/ceilpose_state: enclaves made before ceilpose had a fleet need "
                       "`ceilposectl keys add` again)");
      continue;
    }
    entry.handle = *reader;
  }
  return {};
}

Result<void> DdsFleetSubscriber::take(const std::string& robot, dds_entity_t reader,
                                      FleetSampleSink* sink) {
  std::array<void*, kTakeBatch> samples{};
  std::array<dds_sample_info_t, kTakeBatch> infos{};
  for (;;) {
    samples.fill(nullptr);
    const dds_return_t n = dds_take(reader, samples.data(), infos.data(), kTakeBatch, kTakeBatch);
    if (n < 0) return dds_error("fleet: cannot take samples of rt/" + robot + "/ceilpose_state", n);
    if (n == 0) return {};
    for (dds_return_t k = 0; k < n; ++k) {
      FleetSample sample;
      sample.robot = &robot;
      sample.writer = infos[k].publication_handle;
      if (infos[k].valid_data) {
        sample.pose = from_message(*static_cast<const ceilpose_msg_dds__State_*>(samples[k]));
      } else {
        sample.alive = infos[k].instance_state == DDS_IST_ALIVE;
        if (sample.alive) continue;  // nothing to say
      }
      sink->on_sample(sample);
    }
    if (const dds_return_t rc = dds_return_loan(reader, samples.data(), n); rc != DDS_RETCODE_OK) {
      return dds_error("fleet: cannot return samples of rt/" + robot + "/ceilpose_state", rc);
    }
  }
}

}  // namespace ceilpose
