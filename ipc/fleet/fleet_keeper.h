#pragma once
// Decides what of the fleet's DDS samples reaches the fleet segment: which
// slot a robot gets, which samples are refused (invalid, from the future or
// the past, a second writer under a taken name, no free slot) and when a
// robot turns stale and is removed. The clock is passed in, so tests drive it
// without DDS or sleeping.
//
// Threads: one (the daemon's fleet thread). Allocates only when a robot
// appears; nothing per sample.
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <utility>

#include "ipc/dds/dds_fleet_subscriber.h"
#include "ipc/fleet/fleet_options.h"
#include "ipc/shm/shm_fleet_writer.h"

namespace ceilpose {

enum class FleetEvent { kJoined, kStale, kRemoved, kRefused, kProblem };

class FleetKeeper final : public FleetSampleSink {
 public:
  // What the keeper wants said (the daemon logs it); each refusal reason is
  // reported once per robot, not per sample.
  using Report = std::function<void(FleetEvent, const std::string& message)>;

  FleetKeeper(ShmFleetWriter* writer, FleetOptions options, Report report);

  // FleetSampleSink: stamps with the clocks now.
  void on_sample(const FleetSample& sample) override;
  void on_problem(const std::string& message) override;

  void accept(const FleetSample& sample, int64_t now_mono_ns, int64_t now_real_ns);
  // Marks robots stale and removes them, by their last sample's age.
  void sweep(int64_t now_mono_ns);
  size_t robots() const { return entries_.size(); }

 private:
  struct Entry {
    uint32_t slot = 0;
    uint64_t writer = 0;
    uint64_t last_seq = 0;
    bool stale = false;
    shm::FleetRecord record{};
  };
  void refuse(FleetCounter counter, const std::string& robot, const std::string& why);
  bool wanted(const std::string& robot) const;
  bool free_slot(uint32_t* slot) const;
  void mark_stale(Entry* e, const std::string& robot, const char* why);

  ShmFleetWriter* writer_;
  FleetOptions options_;
  Report report_;
  std::map<std::string, Entry, std::less<>> entries_;
  std::vector<uint8_t> used_;  // per slot
  // (robot, reason) already reported; bounded so a flood of names cannot grow it.
  std::set<std::pair<std::string, int>> reported_;
};

}  // namespace ceilpose
