#include "ipc/shm/shm_common.h"

#include <grp.h>
#include <linux/futex.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <mutex>
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

namespace {

// The SIGBUS handler's table. A slot is claimed by a CAS on `begin` and
// published by storing `end` last; the handler reads only atomics and calls
// only async-signal-safe functions (ftruncate, mmap is a plain system call).
struct GuardSlot {
  std::atomic<uintptr_t> begin{0};  // 0: free; 1: being filled or emptied
  std::atomic<uintptr_t> end{0};    // 0 until the slot is complete
  std::atomic<int> fd{-1};          // kRegrow: the file to grow back
  std::atomic<int> prot{0};         // kDetach: protection of the zero pages
  std::atomic<bool> lost{false};
  std::atomic<uint64_t> regrown{0};
};
// A process maps two segments per reader or writer; 64 is far beyond use.
// A mapping that finds the table full is simply not guarded.
constexpr int kGuardSlots = 64;
GuardSlot g_guards[kGuardSlots];
struct sigaction g_previous_sigbus {};

void forward_sigbus(int sig, siginfo_t* info, void* context) {
  const struct sigaction& prev = g_previous_sigbus;
  if ((prev.sa_flags & SA_SIGINFO) != 0 && prev.sa_sigaction != nullptr) {
    prev.sa_sigaction(sig, info, context);
  } else if (prev.sa_handler != SIG_DFL && prev.sa_handler != SIG_IGN) {
    prev.sa_handler(sig);
  } else {
    // Not ours and nobody else's: die of it as if no handler existed (the
    // faulting access runs again on return).
    signal(SIGBUS, SIG_DFL);
  }
}

void on_sigbus(int sig, siginfo_t* info, void* context) {
  const int saved_errno = errno;
  const auto address = reinterpret_cast<uintptr_t>(info->si_addr);
  for (GuardSlot& slot : g_guards) {
    const uintptr_t end = slot.end.load(std::memory_order_acquire);
    const uintptr_t begin = slot.begin.load(std::memory_order_acquire);
    if (end == 0 || address < begin || address >= end) continue;
    const int fd = slot.fd.load(std::memory_order_relaxed);
    if (fd >= 0 && ::ftruncate(fd, static_cast<off_t>(end - begin)) == 0) {
      slot.regrown.fetch_add(1, std::memory_order_relaxed);
    } else {
      ::mmap(reinterpret_cast<void*>(begin), end - begin, slot.prot.load(std::memory_order_relaxed),
             MAP_FIXED | MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      slot.lost.store(true, std::memory_order_release);
    }
    errno = saved_errno;
    return;
  }
  errno = saved_errno;
  forward_sigbus(sig, info, context);
}

void install_sigbus_handler() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction action {};
    action.sa_sigaction = on_sigbus;
    action.sa_flags = SA_SIGINFO | SA_ONSTACK | SA_RESTART;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGBUS, &action, &g_previous_sigbus);
  });
}

int claim_guard_slot(void* address, size_t size_bytes, int fd, int prot, OnShrink on_shrink) {
  install_sigbus_handler();
  for (int k = 0; k < kGuardSlots; ++k) {
    GuardSlot& slot = g_guards[k];
    uintptr_t expected = 0;
    if (!slot.begin.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) continue;
    slot.fd.store(on_shrink == OnShrink::kRegrow ? fd : -1, std::memory_order_relaxed);
    slot.prot.store(prot, std::memory_order_relaxed);
    slot.lost.store(false, std::memory_order_relaxed);
    slot.regrown.store(0, std::memory_order_relaxed);
    slot.begin.store(reinterpret_cast<uintptr_t>(address), std::memory_order_release);
    slot.end.store(reinterpret_cast<uintptr_t>(address) + size_bytes, std::memory_order_release);
    return k;
  }
  return -1;
}

void release_guard_slot(int k) {
  GuardSlot& slot = g_guards[k];
  slot.end.store(0, std::memory_order_release);
  slot.begin.store(0, std::memory_order_release);
}

}  // namespace

Mapping::Mapping(Mapping&& other) noexcept
    : address_(other.address_), size_bytes_(other.size_bytes_), guard_slot_(other.guard_slot_) {
  other.address_ = nullptr;
  other.size_bytes_ = 0;
  other.guard_slot_ = -1;
}

Mapping& Mapping::operator=(Mapping&& other) noexcept {
  if (this != &other) {
    reset();
    address_ = other.address_;
    size_bytes_ = other.size_bytes_;
    guard_slot_ = other.guard_slot_;
    other.address_ = nullptr;
    other.size_bytes_ = 0;
    other.guard_slot_ = -1;
  }
  return *this;
}

void Mapping::reset() {
  // Unguarded before unmapped: the address range may be reused at once.
  if (guard_slot_ >= 0) release_guard_slot(guard_slot_);
  if (address_ != nullptr) ::munmap(address_, size_bytes_);
  address_ = nullptr;
  size_bytes_ = 0;
  guard_slot_ = -1;
}

bool Mapping::lost() const {
  return guard_slot_ >= 0 && g_guards[guard_slot_].lost.load(std::memory_order_acquire);
}

uint64_t Mapping::regrown() const {
  return guard_slot_ >= 0 ? g_guards[guard_slot_].regrown.load(std::memory_order_relaxed) : 0;
}

Mapping map_shared(int fd, size_t size_bytes, bool writable, OnShrink on_shrink, int* error) {
  const int prot = writable ? (PROT_READ | PROT_WRITE) : PROT_READ;
  void* p = ::mmap(nullptr, size_bytes, prot, MAP_SHARED, fd, 0);
  if (p == MAP_FAILED) {
    *error = -errno;
    return {};
  }
  *error = 0;
  Mapping m(p, size_bytes);
  m.guard_slot_ = claim_guard_slot(p, size_bytes, fd, prot, on_shrink);
  return m;
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
