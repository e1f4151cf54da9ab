#include "ipc/shm/shm_segment_file.h"

#include <fcntl.h>
#include <pwd.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>

#include "core/clock.h"

namespace ceilpose::shm {
namespace {

// Creation races with another creator at most a couple of times.
constexpr int kCreateAttempts = 3;

}  // namespace

uint64_t new_generation() {
  // Unique per start: two writers never share both a pid and a nanosecond.
  const uint64_t g = static_cast<uint64_t>(realtime_ns()) ^
                     (static_cast<uint64_t>(::getpid()) << 40) ^
                     static_cast<uint64_t>(monotonic_ns());
  return g == 0 ? 1 : g;
}

Result<void> set_owner_and_mode(int fd, const std::string& name, mode_t mode, gid_t gid,
                                ShmErrc* code) {
  // fchmod, not the shm_open mode: the process umask must not narrow it.
  if (::fchmod(fd, mode) != 0) {
    const int e = errno;
    return fail(
        code, errc_from_errno(e),
        "cannot set mode " + mode_text(mode) + " on shm segment " + name + ": " + errno_text(e));
  }
  if (::fchown(fd, static_cast<uid_t>(-1), gid) != 0) {
    const int e = errno;
    return fail(code, errc_from_errno(e),
                "cannot give shm segment " + name + " to group id " + std::to_string(gid) + ": " +
                    errno_text(e));
  }
  return {};
}

// What sits at /dev/shm/<name> when it is not a segment this daemon's user
// may replace, for the error message; empty when it is one (a regular file
// of ours) or nothing is there. /dev/shm is world-writable and sticky: any
// local user can put a file, a link or a directory at our name, and only its
// owner or root can remove it.
std::string squatter(const std::string& name) {
  const std::string path = "/dev/shm" + name;
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return {};
  const char* kind = S_ISLNK(st.st_mode)   ? "a symbolic link"
                     : S_ISDIR(st.st_mode) ? "a directory"
                     : S_ISREG(st.st_mode) ? "a file"
                                           : "a special file";
  if (S_ISREG(st.st_mode) && st.st_uid == ::geteuid()) return {};
  const struct passwd* pw = ::getpwuid(st.st_uid);
  return path + " is " + kind + " owned by uid " + std::to_string(st.st_uid) +
         (pw != nullptr ? " (" + std::string(pw->pw_name) + ")" : std::string()) +
         (S_ISREG(st.st_mode)
              ? ", not by this daemon's user (uid " + std::to_string(::geteuid()) + ")"
              : std::string(", not a shared-memory segment")) +
         ": remove it (as its owner or root) or choose another ipc.shm_name";
}

// Creates `name` exclusively and locks it. An existing segment is replaced
// only when no live writer holds its lock (flock is dropped by the kernel when
// the owner dies, whatever the pid namespace).
Result<UniqueFd> claim_name(const std::string& name, mode_t mode, const SegmentOwnerHooks& hooks,
                            ShmErrc* code) {
  UniqueFd fd;
  for (int attempt = 0; attempt < kCreateAttempts && !fd.valid(); ++attempt) {
    fd = UniqueFd(::shm_open(name.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, mode));
    if (fd.valid()) break;
    const int e = errno;
    if (e != EEXIST) {
      return fail(code, errc_from_errno(e),
                  "cannot create shm segment " + name + " (mode " + mode_text(mode) +
                      "): " + errno_text(e));
    }
    if (const std::string taken = squatter(name); !taken.empty())
      return fail(code, ShmErrc::kNameTaken, "cannot create shm segment " + name + ": " + taken);
    UniqueFd old(::shm_open(name.c_str(), O_RDWR | O_CLOEXEC, 0));
    if (!old.valid()) {
      const int oe = errno;
      if (oe == ENOENT) continue;  // removed meanwhile: try again
      return fail(code, errc_from_errno(oe),
                  "shm segment " + name +
                      " exists and cannot be opened to check its writer: " + errno_text(oe));
    }
    if (::flock(old.get(), LOCK_EX | LOCK_NB) != 0) {
      const int le = errno;
      if (le == EWOULDBLOCK) {
        const int pid = hooks.writer_pid != nullptr ? hooks.writer_pid(old.get()) : 0;
        return fail(code, ShmErrc::kLiveWriter,
                    "another ceilposed (pid " + (pid > 0 ? std::to_string(pid) : "unknown") +
                        ") is publishing on " + name);
      }
      return fail(code, ShmErrc::kSystem,
                  "cannot lock shm segment " + name + ": " + errno_text(le));
    }
    // Its writer is gone: replace it. Unlink while holding its lock so a
    // concurrent creator sees it as owned.
    if (hooks.before_replace != nullptr) hooks.before_replace(old.get());
    if (::shm_unlink(name.c_str()) != 0 && errno != ENOENT) {
      const int ue = errno;
      return fail(code, errc_from_errno(ue),
                  "cannot remove stale shm segment " + name + ": " + errno_text(ue));
    }
  }
  if (!fd.valid()) {
    return fail(code, ShmErrc::kLiveWriter,
                "shm segment " + name + " keeps being re-created by another process");
  }
  // Between O_EXCL and this lock another creator could only see an empty,
  // unlocked segment; it would replace it and our lock still wins on ours.
  if (::flock(fd.get(), LOCK_EX | LOCK_NB) != 0) {
    const int le = errno;
    return fail(code, ShmErrc::kLiveWriter,
                "cannot lock new shm segment " + name + ": " + errno_text(le));
  }
  return fd;
}

// Sizes and maps a segment that `fd` holds.
Result<Mapping> size_and_map(int fd, const std::string& name, size_t size_bytes, ShmErrc* code) {
  if (::ftruncate(fd, static_cast<off_t>(size_bytes)) != 0) {
    const int e = errno;
    return fail(code, errc_from_errno(e),
                "cannot size shm segment " + name + " to " + std::to_string(size_bytes) +
                    " bytes: " + errno_text(e));
  }
  int map_error = 0;
  Mapping mapping = map_shared(fd, size_bytes, true, OnShrink::kRegrow, &map_error);
  if (mapping.get() == nullptr) {
    return fail(code, errc_from_errno(map_error),
                "cannot map shm segment " + name + " (" + std::to_string(size_bytes) +
                    " bytes): " + errno_text(map_error));
  }
  return mapping;
}

// Owner and mode of a segment we may not be allowed to open, for the message.
std::string describe_access(const std::string& name) {
  struct stat st {};
  const std::string path = "/dev/shm" + name;  // where Linux keeps POSIX shm
  std::string text;
  if (::stat(path.c_str(), &st) == 0) {
    text = "segment is mode " + mode_text(st.st_mode) + ", owner uid " + std::to_string(st.st_uid) +
           " gid " + std::to_string(st.st_gid) + ", " + std::to_string(st.st_size) + " bytes; ";
  }
  return text + "this process is uid " + std::to_string(::geteuid()) + " gid " +
         std::to_string(::getegid()) + " (is it in the segment's group?)";
}

namespace {

// A writer sizes and fills a new segment within milliseconds of creating it;
// one still empty or without a header after this long is not being created
// by anyone (another program's file, or a writer that died creating it).
constexpr int64_t kCreationGraceNs = 2'000'000'000;

// Seconds since the segment's size last changed (ftruncate sets the mtime).
double seconds_since_sized(const struct stat& st) {
  const int64_t sized_ns = int64_t{st.st_mtim.tv_sec} * 1'000'000'000 + st.st_mtim.tv_nsec;
  return static_cast<double>(realtime_ns() - sized_ns) * 1e-9;
}

}  // namespace

// kNotReady while a writer could still be creating the segment, kBadMagic
// once none can be.
Error not_ready_or_foreign(const std::string& name, const struct stat& st, const std::string& what,
                           ShmErrc* code) {
  const double age_s = seconds_since_sized(st);
  if (age_s * 1e9 < static_cast<double>(kCreationGraceNs)) {
    return fail(code, ShmErrc::kNotReady,
                "shm segment " + name + " is " + what + ": its writer is still creating it");
  }
  char age[32];
  std::snprintf(age, sizeof age, "%.0f s", age_s);
  return fail(code, ShmErrc::kBadMagic,
              "shm segment " + name + " is " + what + " " + age +
                  " after it was sized: not a ceilpose segment (another program's file, or a "
                  "writer that died creating it); remove /dev/shm" +
                  name + " (as its owner or root)");
}

Result<OpenedSegment> open_segment_readonly(const std::string& name, const SegmentShape& shape,
                                            ShmErrc* code) {
  OpenedSegment out;
  out.fd = UniqueFd(::shm_open(name.c_str(), O_RDONLY | O_CLOEXEC, 0));
  if (!out.fd.valid()) {
    const int e = errno;
    if (e == ENOENT) {
      return fail(code, ShmErrc::kNotFound,
                  "no shm segment " + name + " (no ceilposed publishing on it; is it running " +
                      "with --shm " + shape.daemon_shm + "?)");
    }
    if (e == EACCES) {
      return fail(code, ShmErrc::kPermission,
                  "permission denied opening shm segment " + name + ": " + describe_access(name));
    }
    return fail(code, errc_from_errno(e), "cannot open shm segment " + name + ": " + errno_text(e));
  }
  if (::fstat(out.fd.get(), &out.st) != 0) {
    const int e = errno;
    return fail(code, ShmErrc::kSystem, "cannot stat shm segment " + name + ": " + errno_text(e));
  }
  const auto size_bytes = static_cast<size_t>(out.st.st_size);
  if (size_bytes == 0) return not_ready_or_foreign(name, out.st, "empty", code);
  if (size_bytes < shape.identity_bytes) {
    return fail(code, ShmErrc::kBadSize,
                "shm segment " + name + " is " + std::to_string(size_bytes) +
                    " bytes, too small for a ceilpose " + shape.kind + " header (" +
                    std::to_string(shape.identity_bytes) + " bytes at least)");
  }
  int map_error = 0;
  out.mapping = map_shared(out.fd.get(), std::min(size_bytes, shape.map_limit_bytes), false,
                           OnShrink::kDetach, &map_error);
  if (out.mapping.get() == nullptr) {
    return fail(code, errc_from_errno(map_error),
                "cannot map shm segment " + name + " (" + std::to_string(size_bytes) +
                    " bytes): " + errno_text(map_error));
  }
  return out;
}

}  // namespace ceilpose::shm
