#pragma once
// Pieces shared by the writer and the reader: typed errors, RAII owners of the
// descriptor and the mapping, the futex calls. Thin system wrappers return
// -errno and never log; callers turn them into messages with context.
#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/result.h"
#include "core/unique_fd.h"

namespace ceilpose::shm {

// Typed errors; the values are the C client's CEILPOSE_ERR_* codes.
enum class ShmErrc : int {
  kOk = 0,
  kInvalidArgument = -1,
  kNotFound = -2,
  kPermission = -3,
  kAbiMismatch = -4,
  kBadSize = -5,
  kBadMagic = -6,
  kNotReady = -7,
  kSystem = -8,
  kNoMemory = -9,
  kLiveWriter = -15,
  kNoGroup = -16,
  // The writer's own (no C client sees it): the name is held by something
  // the daemon must not and cannot replace: another user's file, a symbolic
  // link or a directory in /dev/shm.
  kNameTaken = -19,
};

// Stores `code` in *out (if given) and returns the error with `message`.
Error fail(ShmErrc* out, ShmErrc code, std::string message);

// A POSIX shm name: "/" then 1..249 printable characters without another "/"
// (room is left for the "-wake" suffix); kShmNameRule says so in messages.
bool valid_shm_name(const std::string& name);
inline constexpr const char* kShmNameRule =
    "'/' followed by 1-249 printable characters without '/' or space (not '/.' or '/..')";
std::string wake_segment_name(const std::string& name);

// What a mapping does when the file under it shrinks (truncate(1) by the
// segment's owner or root). Touching a page past the new end raises SIGBUS,
// which kills the process unless handled; map_shared() installs a handler
// (once per process, chaining to any handler installed before it) that
// repairs a fault inside a registered mapping and returns:
// What other processes (the owner's user or root) did to a live segment
// and its writer repaired, counted since creation.
struct SegmentDamage {
  uint64_t truncations = 0;     // found shrunk and grown back
  uint64_t header_repairs = 0;  // header found overwritten and restored
};

enum class OnShrink {
  kRegrow,  // the writer: ftruncate(2) the file back to the mapped size; the
            // access then lands on fresh zero pages, which the writer refills
  kDetach,  // a reader: put anonymous zero pages over the whole mapping and
            // mark it lost(); the reader re-opens the name (Liveness::kRestarted)
};

class Mapping {
 public:
  Mapping() = default;
  Mapping(void* address, size_t size_bytes) : address_(address), size_bytes_(size_bytes) {}
  ~Mapping() { reset(); }
  Mapping(Mapping&& other) noexcept;
  Mapping& operator=(Mapping&& other) noexcept;
  Mapping(const Mapping&) = delete;
  Mapping& operator=(const Mapping&) = delete;

  void* get() const { return address_; }
  size_t size_bytes() const { return size_bytes_; }
  void reset();
  // kDetach: the file shrank under this mapping, which now holds zeros.
  bool lost() const;
  // kRegrow: how many times the file was found shrunk and grown back.
  uint64_t regrown() const;

 private:
  friend Mapping map_shared(int fd, size_t size_bytes, bool writable, OnShrink on_shrink,
                            int* error);
  void* address_ = nullptr;
  size_t size_bytes_ = 0;
  int guard_slot_ = -1;  // its entry in the SIGBUS handler's table, -1: none
};

// mmap(MAP_SHARED) of `size_bytes` of `fd`, guarded against the file
// shrinking (see OnShrink; kRegrow keeps using `fd`, which must outlive the
// mapping); returns -errno in *error on failure.
Mapping map_shared(int fd, size_t size_bytes, bool writable, OnShrink on_shrink, int* error);

// kill(pid, 0): true unless the process certainly does not exist (ESRCH).
bool process_exists(int pid);

// "rw-r-----"-style text of the low 9 mode bits, for messages.
std::string mode_text(unsigned mode);
// Describes errno values in messages: "Permission denied (EACCES)".
std::string errno_text(int error);

// The group id of `group` (the process's own group when empty); the error
// names the group and the segment it was for.
Result<gid_t> lookup_group(const std::string& group, const std::string& segment, ShmErrc* code);
// Classifies an errno from shm_open/mmap into a typed error.
ShmErrc errc_from_errno(int error);

}  // namespace ceilpose::shm
