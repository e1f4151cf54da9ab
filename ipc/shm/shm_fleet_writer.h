#pragma once
// The daemon's side of the fleet segment "<shm>-fleet" (ipc/shm/fleet_layout.h,
// docs/fleet.md): a fixed number of slots, one robot each, written by one
// thread. Which robot goes in which slot is the caller's business (the
// fleet keeper); this class only lays out, stores, clears and counts.
//
// Threads: everything from one thread. Nothing allocates, waits or throws
// after create().
#include <cstdint>
#include <memory>
#include <string>

#include "core/result.h"
#include "ipc/shm/fleet_layout.h"
#include "ipc/shm/shm_common.h"

namespace ceilpose {

struct ShmFleetOptions {
  std::string name;   // the fleet segment's own name, e.g. "/ceilpose-fleet"
  std::string group;  // readable by this group (mode 0640); empty: the process's
  uint32_t capacity = 256;
  uint32_t stale_after_ms = 1000;  // published for readers (fleet.stale_after_ms)
};

// The fleet segment's name for a pose segment name: "/ceilpose" -> "/ceilpose-fleet".
std::string fleet_segment_name(const std::string& shm_name);

enum class FleetCounter {
  kAccepted,
  kRefusedFull,
  kRefusedFuture,
  kRefusedPast,
  kRefusedInvalid,
  kRefusedDuplicate,
  kRemoved,
};

class ShmFleetWriter {
 public:
  // Creates the segment, replacing one left by a dead writer; refuses
  // (kLiveWriter) one a live writer holds and (kNameTaken) a squatted name.
  static Result<ShmFleetWriter> create(const ShmFleetOptions& options,
                                       shm::ShmErrc* code = nullptr);
  static Result<void> remove(const std::string& name);

  ShmFleetWriter(ShmFleetWriter&&) noexcept;
  ShmFleetWriter& operator=(ShmFleetWriter&&) noexcept;
  ~ShmFleetWriter();

  uint32_t capacity() const;
  // Writes `record` into `slot` (< capacity) and counts the slot as used.
  void store(uint32_t slot, const shm::FleetRecord& record);
  // Frees `slot`: readers see no robot there any more.
  void clear(uint32_t slot);
  void count(FleetCounter counter, uint64_t n = 1);
  uint64_t counted(FleetCounter counter) const;
  uint32_t robots() const;
  // Refreshes the heartbeat, and first restores the header (identity, state,
  // robot counts) if another process overwrote it or a truncation zeroed it.
  void heartbeat();
  // State "running" once the keeper runs, "stopped" when the daemon stops.
  void mark_running();
  void mark_stopped();
  const std::string& name() const;
  // Times the segment was found truncated (SIGBUS) and grown back.
  uint64_t truncations() const;
  // Times heartbeat() found the header overwritten and restored it. Any thread.
  uint64_t header_repairs() const;

 private:
  struct Impl;
  explicit ShmFleetWriter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace ceilpose
