#pragma once
// Creating a shared-memory segment that one live writer owns: the name
// claimed exclusively and flock()ed (a segment left by a dead writer is
// replaced, one held by a live writer or squatted by another user is not),
// its mode and group set, sized and mapped. The pose segment and the fleet
// segment are made the same way.
#include <sys/stat.h>
#include <sys/types.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/result.h"
#include "core/unique_fd.h"
#include "ipc/shm/shm_common.h"

namespace ceilpose::shm {

// What claim_name asks of the segment's kind about an existing one.
struct SegmentOwnerHooks {
  // The pid its header names, for the "live writer" message; 0 if unknown.
  int (*writer_pid)(int fd) = nullptr;
  // Called before a dead writer's segment is unlinked (e.g. to wake readers).
  void (*before_replace)(int fd) = nullptr;
};

// The writer pid in the header (type Header: `magic`, `writer_pid`) of an
// existing segment, for the "live writer" message; 0 when the file is not a
// complete segment of that kind.
template <typename Header>
int header_writer_pid(int fd, uint64_t magic) {
  struct stat st {};
  if (::fstat(fd, &st) != 0 || static_cast<size_t>(st.st_size) < sizeof(Header)) return 0;
  int error = 0;
  Mapping m = map_shared(fd, sizeof(Header), false, OnShrink::kDetach, &error);
  if (m.get() == nullptr) return 0;
  const auto* header = static_cast<const Header*>(m.get());
  return header->magic.load(std::memory_order_acquire) == magic ? header->writer_pid : 0;
}

// Unique per writer start.
uint64_t new_generation();

// Creates `name` exclusively (mode `mode`) and locks it; an existing segment
// is replaced only when no live writer holds its lock.
Result<UniqueFd> claim_name(const std::string& name, mode_t mode, const SegmentOwnerHooks& hooks,
                            ShmErrc* code);

// What sits at /dev/shm/<name> when it is not a segment this process's user
// may replace (for the message); empty when it may.
std::string squatter(const std::string& name);

// fchmod + fchown(group) of a segment, the message naming it.
Result<void> set_owner_and_mode(int fd, const std::string& name, mode_t mode, gid_t gid,
                                ShmErrc* code);

// ftruncate to `size_bytes` and map read-write, grown back if truncated.
Result<Mapping> size_and_map(int fd, const std::string& name, size_t size_bytes, ShmErrc* code);

// ---- Readers ----

// An open segment: its fd, its read-only mapping and what fstat said.
struct OpenedSegment {
  UniqueFd fd;
  Mapping mapping;
  struct stat st {};
};

// What open_segment_readonly expects of a segment, for its checks and messages.
struct SegmentShape {
  const char* kind;        // "pose", "fleet"
  size_t identity_bytes;   // the smallest file that holds the header's identity
  size_t map_limit_bytes;  // map at most this much
  std::string daemon_shm;  // the --shm the daemon would be started with
};

// Opens `name` read-only and maps it (kDetach on shrink), refusing one that is
// missing, not permitted (naming owner and mode), empty or too small.
Result<OpenedSegment> open_segment_readonly(const std::string& name, const SegmentShape& shape,
                                            ShmErrc* code);

// kNotReady while a writer could still be creating the segment (it was sized
// moments ago), kBadMagic once none can be; `what`: "empty", "without a header".
Error not_ready_or_foreign(const std::string& name, const struct stat& st, const std::string& what,
                           ShmErrc* code);

// Owner and mode of a segment we may not be allowed to open, for the message.
std::string describe_access(const std::string& name);

}  // namespace ceilpose::shm
