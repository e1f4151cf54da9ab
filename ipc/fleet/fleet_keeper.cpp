#include "ipc/fleet/fleet_keeper.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>

#include "core/clock.h"

namespace ceilpose {
namespace {

// Distinct (robot, reason) pairs reported before the keeper stops naming them.
constexpr size_t kMaxReported = 1024;

// A pose a controller could act on: valid, every number finite, variances
// not negative. What arrives over the network is checked like a file.
bool plausible(const PoseRecord& p) {
  if (!pose_is_valid(p) || !pose_numbers_finite(p)) return false;
  for (int i = 0; i < 3; ++i)
    if (p.covariance[i * 4] < 0.0) return false;
  return true;
}

}  // namespace

FleetKeeper::FleetKeeper(ShmFleetWriter* writer, FleetOptions options, Report report)
    : writer_(writer),
      options_(std::move(options)),
      report_(std::move(report)),
      used_(writer->capacity(), 0) {}

void FleetKeeper::on_sample(const FleetSample& sample) {
  accept(sample, monotonic_ns(), realtime_ns());
}

void FleetKeeper::on_problem(const std::string& message) {
  if (report_) report_(FleetEvent::kProblem, message);
}

bool FleetKeeper::wanted(const std::string& robot) const {
  return options_.robots.empty() ||
         std::find(options_.robots.begin(), options_.robots.end(), robot) != options_.robots.end();
}

bool FleetKeeper::free_slot(uint32_t* slot) const {
  const auto it = std::find(used_.begin(), used_.end(), 0);
  if (it == used_.end()) return false;
  *slot = static_cast<uint32_t>(it - used_.begin());
  return true;
}

void FleetKeeper::refuse(FleetCounter counter, const std::string& robot, const std::string& why) {
  writer_->count(counter);
  if (!report_ || reported_.size() >= kMaxReported) return;
  if (!reported_.emplace(robot, static_cast<int>(counter)).second) return;
  report_(FleetEvent::kRefused, "fleet: refusing samples of robot '" + robot + "': " + why +
                                    " (reported once; counted in `ceilposectl fleet --shm`)");
}

void FleetKeeper::mark_stale(Entry* e, const std::string& robot, const char* why) {
  if (e->stale) return;
  e->stale = true;
  e->record.fleet_flags |= CEILPOSE_FLEET_STALE;
  writer_->store(e->slot, e->record);
  if (report_) report_(FleetEvent::kStale, "fleet: robot '" + robot + "' is stale: " + why);
}

void FleetKeeper::accept(const FleetSample& sample, int64_t now_mono_ns, int64_t now_real_ns) {
  const std::string& robot = *sample.robot;
  if (!wanted(robot)) return;
  auto it = entries_.find(robot);
  if (!sample.alive) {
    if (it != entries_.end() && it->second.writer == sample.writer)
      mark_stale(&it->second, robot, "its DDS writer left or lost liveliness");
    return;
  }
  if (robot.size() >= CEILPOSE_ROBOT_NAME_SIZE) {
    refuse(FleetCounter::kRefusedInvalid, robot.substr(0, CEILPOSE_ROBOT_NAME_SIZE - 1) + "...",
           "name longer than " + std::to_string(CEILPOSE_ROBOT_NAME_SIZE - 1) + " characters");
    return;
  }
  if (!plausible(sample.pose)) {
    refuse(FleetCounter::kRefusedInvalid, robot,
           "invalid pose (not marked valid, a non-finite number or a negative variance)");
    return;
  }
  const int64_t latency_ns = now_real_ns - sample.pose.capture_real_ns;
  const int64_t offset_ns = int64_t{options_.max_clock_offset_ms} * kMsNs;
  if (latency_ns < -offset_ns) {
    refuse(FleetCounter::kRefusedFuture, robot,
           "stamped " + std::to_string(-latency_ns / kMsNs) +
               " ms in the future of this robot's clock (fleet.max_clock_offset_ms " +
               std::to_string(options_.max_clock_offset_ms) + "): are the clocks synchronised?");
    return;
  }
  if (latency_ns > offset_ns + int64_t{options_.stale_after_ms} * kMsNs) {
    refuse(FleetCounter::kRefusedPast, robot,
           "stamped " + std::to_string(latency_ns / kMsNs) +
               " ms in the past (more than fleet.max_clock_offset_ms + fleet.stale_after_ms = " +
               std::to_string(options_.max_clock_offset_ms + options_.stale_after_ms) +
               " ms): are the clocks synchronised?");
    return;
  }
  if (it != entries_.end() && it->second.writer != sample.writer) {
    if (!it->second.stale) {
      refuse(FleetCounter::kRefusedDuplicate, robot,
             "a second DDS writer publishes under this name (two robots named alike?); the "
             "first one keeps the slot");
      return;
    }
    it->second.writer = sample.writer;  // the robot came back (restarted): same slot
    it->second.last_seq = 0;
  }
  if (it == entries_.end()) {
    uint32_t slot = 0;
    if (!free_slot(&slot)) {
      refuse(FleetCounter::kRefusedFull, robot,
             "all " + std::to_string(used_.size()) +
                 " slots of the fleet segment are taken (raise fleet.capacity)");
      return;
    }
    Entry e;
    e.slot = slot;
    e.writer = sample.writer;
    std::memcpy(e.record.robot, robot.c_str(), robot.size() + 1);
    it = entries_.emplace(robot, e).first;
    used_[slot] = 1;
    if (report_)
      report_(FleetEvent::kJoined, "fleet: robot '" + robot + "' joined (slot " +
                                       std::to_string(slot) + ", " +
                                       std::to_string(entries_.size()) + " robots)");
  }
  Entry& e = it->second;
  shm::FleetRecord& r = e.record;
  if (e.last_seq != 0 && sample.pose.seq > e.last_seq + 1)
    r.lost += static_cast<uint32_t>(std::min<uint64_t>(sample.pose.seq - e.last_seq - 1, 1u << 30));
  e.last_seq = sample.pose.seq;
  r.pose = sample.pose;
  // Its exposure on this robot's monotonic clock: the realtime stamp moved by
  // this robot's realtime-monotonic offset now.
  r.pose.capture_mono_ns = sample.pose.capture_real_ns - (now_real_ns - now_mono_ns);
  r.pose.publish_mono_ns = 0;
  r.pose.publish_real_ns = 0;
  r.received_mono_ns = now_mono_ns;
  r.latency_ns = latency_ns;
  ++r.samples;
  r.fleet_flags = 0;
  e.stale = false;
  writer_->store(e.slot, r);
  writer_->count(FleetCounter::kAccepted);
}

void FleetKeeper::sweep(int64_t now_mono_ns) {
  const int64_t stale_ns = int64_t{options_.stale_after_ms} * kMsNs;
  const int64_t remove_ns = int64_t{options_.remove_after_ms} * kMsNs;
  for (auto it = entries_.begin(); it != entries_.end();) {
    Entry& e = it->second;
    const int64_t age_ns = now_mono_ns - e.record.received_mono_ns;
    if (age_ns > remove_ns) {
      writer_->clear(e.slot);
      used_[e.slot] = 0;
      writer_->count(FleetCounter::kRemoved);
      if (report_)
        report_(FleetEvent::kRemoved, "fleet: robot '" + it->first + "' removed after " +
                                          std::to_string(age_ns / kMsNs) + " ms without a sample");
      it = entries_.erase(it);
      continue;
    }
    if (age_ns > stale_ns) mark_stale(&e, it->first, "no sample for fleet.stale_after_ms");
    ++it;
  }
}

}  // namespace ceilpose
