#pragma once
// The daemon's side of the pose segment (docs/ipc.md).
//
// Lifecycle:
//   create()  --> state "starting" (segment exists, heartbeat running, no pose)
//   publish() --> state "running"
//   mark_stopped() --> state "stopped"; readers blocked in wait_next return
//   destructor: unmaps; the segment is NOT unlinked, so readers keep seeing
//   "stopped" until the next writer replaces it (remove() unlinks it).
//
// Threads: publish(), update_status() and mark_stopped() from one thread (the
// single seqlock writer); heartbeat() from any thread. Nothing here waits for
// readers, allocates or throws after create().
#include <cstdint>
#include <memory>
#include <string>

#include "core/result.h"
#include "ipc/shm/pose_record.h"
#include "ipc/shm/shm_common.h"

namespace ceilpose {

struct ShmOptions {
  std::string name = CEILPOSE_DEFAULT_SHM_NAME;  // POSIX shm name, "/" + no other "/"
  // Group that may read the segment (mode 0640). Empty: the process's group.
  // A name that does not exist is an error, never silently ignored.
  std::string group;
  // A writer thread refreshes the header heartbeat at this period so readers
  // can tell a live daemon from a dead one even with no pose coming; readers
  // judge staleness against a threshold well above it. 0: no thread, the
  // caller must call heartbeat() at least every 100 ms.
  int heartbeat_period_ms = 50;
  // Published in the segment: readers call a heartbeat or pose older than
  // this stale unless they are given their own threshold (ipc.stale_after_ms).
  int stale_after_ms = 500;
};

class ShmPoseWriter {
 public:
  // Creates the segment `options.name` (and its "-wake" companion), replacing a
  // segment left by a writer that is gone; refuses (ShmErrc::kLiveWriter) when
  // a live writer holds it. `code`, if given, receives the typed error.
  static Result<ShmPoseWriter> create(const ShmOptions& options, shm::ShmErrc* code = nullptr);

  // Unlinks the segment and its companion (tests, uninstall). Missing is fine.
  static Result<void> remove(const std::string& name);

  ShmPoseWriter(ShmPoseWriter&&) noexcept;
  ShmPoseWriter& operator=(ShmPoseWriter&&) noexcept;
  ~ShmPoseWriter();

  // Publishes `pose` as the latest and into the ring. Fills pose.seq and, when
  // zero, the publish times. Wakes blocked readers only if any are registered.
  void publish(const PoseRecord& pose);
  // Replaces the status record (ceilposectl status). Stamps updated_mono_ns
  // when zero.
  void update_status(const StatusRecord& status);
  // Refreshes the heartbeat (also done by publish() and the heartbeat
  // thread) and restores the header's identity if something overwrote it.
  void heartbeat();
  // Times the header's identity was found overwritten and restored (by
  // heartbeat() or the heartbeat thread): the daemon says so in its log.
  uint64_t header_repairs() const;
  // Times the segment or its -wake companion was found truncated (SIGBUS on
  // a write) and grown back to its size; the zeroed header is then restored
  // like an overwritten one.
  uint64_t truncations() const;
  // State "stopped", wakes every blocked reader. Call on SIGTERM. Ends the
  // heartbeat thread (waits for it, at most one period), so the last
  // heartbeat is the stop time.
  void mark_stopped();

  const std::string& name() const;
  uint64_t generation() const;
  uint64_t last_seq() const;  // 0 before the first publish
  // FUTEX_WAKE calls made so far: publish() makes one only when a reader is
  // registered as waiting, so this stays 0 with no blocked readers.
  uint64_t wake_syscalls() const;
  // Readers registered as blocked in wait_next right now (the -wake
  // segment's count), e.g. for a test to publish only once one sleeps.
  uint32_t waiting_readers() const;

 private:
  struct Impl;
  explicit ShmPoseWriter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace ceilpose
