#include "ipc/shm/shm_common.h"

#include <grp.h>
#include <linux/futex.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <vector>

namespace ceilpose::shm {

Error fail(ShmErrc* out, ShmErrc code, std::string message) {
  if (out != nullptr) *out = code;
  return make_error(std::move(message));
}

bool valid_shm_name(const std::string& name) {
  // NAME_MAX (255) minus room for the "-wake" companion suffix; "/." and
  // "/.." are /dev/shm's directories, and a space or control character is a
  // quoting accident, not a name.
  if (name.size() < 2 || name.size() > 250 || name[0] != '/') return false;
  if (name == "/." || name == "/..") return false;
  for (size_t k = 1; k < name.size(); ++k) {
    const auto c = static_cast<unsigned char>(name[k]);
    if (c == '/' || c <= ' ' || c == 0x7f) return false;
  }
  return true;
}

Result<gid_t> lookup_group(const std::string& group, const std::string& segment, ShmErrc* code) {
  if (group.empty()) return ::getegid();
  std::vector<char> buffer(16384);
  struct group entry {};
  struct group* found = nullptr;
  int rc = 0;
  while ((rc = ::getgrnam_r(group.c_str(), &entry, buffer.data(), buffer.size(), &found)) ==
             ERANGE &&
         buffer.size() < (1u << 20)) {
    buffer.resize(buffer.size() * 4);
  }
  if (rc != 0) {
    return fail(code, ShmErrc::kSystem,
                "cannot look up group '" + group + "' for shm segment " + segment + ": " +
                    shm::errno_text(rc));
  }
  if (found == nullptr) {
    return fail(code, ShmErrc::kNoGroup,
                "group '" + group + "' for shm segment " + segment + " does not exist");
  }
  return found->gr_gid;
}

std::string wake_segment_name(const std::string& name) { return name + "-wake"; }

Mapping::Mapping(Mapping&& other) noexcept
    : address_(other.address_), size_bytes_(other.size_bytes_) {
  other.address_ = nullptr;
  other.size_bytes_ = 0;
}

Mapping& Mapping::operator=(Mapping&& other) noexcept {
  if (this != &other) {
    reset();
    address_ = other.address_;
    size_bytes_ = other.size_bytes_;
    other.address_ = nullptr;
    other.size_bytes_ = 0;
  }
  return *this;
}

void Mapping::reset() {
  if (address_ != nullptr) ::munmap(address_, size_bytes_);
  address_ = nullptr;
  size_bytes_ = 0;
}

Mapping map_shared(int fd, size_t size_bytes, bool writable, int* error) {
  const int prot = writable ? (PROT_READ | PROT_WRITE) : PROT_READ;
  void* p = ::mmap(nullptr, size_bytes, prot, MAP_SHARED, fd, 0);
  if (p == MAP_FAILED) {
    *error = -errno;
    return {};
  }
  *error = 0;
  return Mapping(p, size_bytes);
}

bool process_exists(int pid) {
  if (pid <= 0) return false;
  // EPERM means it exists but belongs to someone else.
  return ::kill(pid, 0) == 0 || errno != ESRCH;
}

std::string mode_text(unsigned mode) {
  const char* kChars = "rwxrwxrwx";
  std::string text(9, '-');
  for (int i = 0; i < 9; ++i) {
    if ((mode & (0400u >> i)) != 0) text[i] = kChars[i];
  }
  char octal[8];
  std::snprintf(octal, sizeof octal, "%04o", mode & 0777u);
  return std::string(octal) + " (" + text + ")";
}

std::string errno_text(int error) {
  if (error < 0) error = -error;
  const char* name = strerrorname_np(error);
  return std::string(std::strerror(error)) + " (" + (name != nullptr ? name : "?") + ")";
}

ShmErrc errc_from_errno(int error) {
  if (error < 0) error = -error;
  switch (error) {
    case ENOENT:
      return ShmErrc::kNotFound;
    case EACCES:
    case EPERM:
      return ShmErrc::kPermission;
    case ENOMEM:
      return ShmErrc::kNoMemory;
    case EINVAL:
    case ENAMETOOLONG:
      return ShmErrc::kInvalidArgument;
    default:
      return ShmErrc::kSystem;
  }
}

}  // namespace ceilpose::shm
