#pragma once
// A reader of the pose segment (ceilposectl, the C client, tests).
//
// Liveness rules (docs/ipc.md): a reader judges its writer by, in order,
//   restarted — the name now refers to another segment (a new writer): reattach();
//   stopped   — the writer marked the segment stopped (clean shutdown);
//   dead      — kill(writer_pid, 0) fails with ESRCH;
//   stale     — the heartbeat (refreshed every 50 ms by default) is older than
//               the caller's threshold;
//   starting  — alive, no pose published yet;
//   live      — otherwise.
//
// Threads: one thread per reader object (readers are cheap: open one each).
// read_latest(), read_status() and wait_next() never allocate or throw.
#include <cstdint>
#include <memory>
#include <string>

#include "core/result.h"
#include "ipc/shm/pose_record.h"
#include "ipc/shm/shm_common.h"

namespace ceilpose {

enum class ReadResult { kOk, kNoPose, kBusy };
enum class WaitResult { kPose, kTimeout, kStopped, kWriterDead, kBusy };
enum class Liveness { kLive, kStarting, kStopped, kStale, kWriterDead, kRestarted };

const char* to_string(ReadResult r);
const char* to_string(WaitResult r);
const char* to_string(Liveness l);

struct WriterInfo {
  int pid = 0;
  WriterState state = WriterState::kStarting;
  uint64_t generation = 0;
  int64_t start_mono_ns = 0;
  int64_t start_real_ns = 0;
  int64_t heartbeat_mono_ns = 0;
  int64_t stale_after_ms = 0;  // the writer's staleness threshold (ipc.stale_after_ms)
};

class ShmPoseReader {
 public:
  // Copy attempts before a read reports kBusy (the writer never waits for us).
  static constexpr int kReadRetries = 256;

  // Opens `name` read-only (and its "-wake" companion read-write) and checks
  // magic, ABI version and size. Errors name the segment, its size and mode.
  static Result<ShmPoseReader> open(const std::string& name, shm::ShmErrc* code = nullptr);
  // Like open(), but while the segment is missing or still being initialized
  // waits (inotify on /dev/shm, re-checked at least every 250 ms) up to
  // timeout_ms (< 0: forever) for a daemon to create it.
  static Result<ShmPoseReader> open_waiting(const std::string& name, int timeout_ms,
                                            shm::ShmErrc* code = nullptr);

  ShmPoseReader(ShmPoseReader&&) noexcept;
  ShmPoseReader& operator=(ShmPoseReader&&) noexcept;
  ~ShmPoseReader();

  ReadResult read_latest(PoseRecord* out) const;
  // Blocks on the futex until a pose with seq > after_seq exists (returns the
  // newest), the writer stops or dies, or timeout_ms passes (< 0: forever).
  // Also returns the newest pose when the sequence went back below one this
  // reader saw (the segment was written over): its seq is then <= after_seq.
  WaitResult wait_next(uint64_t after_seq, int timeout_ms, PoseRecord* out);
  // stale_after_ms <= 0: the writer's own threshold (WriterInfo::stale_after_ms).
  Liveness liveness(int64_t stale_after_ms = 0) const;
  // `requested` when positive, else the writer's threshold.
  int64_t stale_after_ms(int64_t requested = 0) const;
  ReadResult read_status(StatusRecord* out) const;
  // Up to max_poses recent poses, newest first; returns how many.
  int read_recent(PoseRecord* out, int max_poses) const;
  WriterInfo writer_info() const;
  uint64_t latest_seq() const;
  // True when the name now refers to another segment than the one mapped,
  // or the segment was truncated under this reader (lost()).
  bool replaced() const;
  // The file shrank under the mapping (truncate(1) by its owner or root):
  // what was mapped now reads as zeros; reattach() to the name.
  bool lost() const;
  // Re-opens the name; on success this reader switches to the new segment,
  // on failure it keeps the old one.
  Result<void> reattach(shm::ShmErrc* code = nullptr);
  const std::string& name() const;

 private:
  struct Impl;
  explicit ShmPoseReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace ceilpose
