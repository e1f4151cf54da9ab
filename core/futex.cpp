#include "core/futex.h"

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <ctime>

namespace ceilpose {
namespace {

int op(int base, FutexScope scope) {
  return scope == FutexScope::kProcess ? (base | FUTEX_PRIVATE_FLAG) : base;
}

}  // namespace

int futex_wait(const std::atomic<uint32_t>* word, uint32_t expected, int64_t timeout_ns,
               FutexScope scope) {
  timespec ts{};
  timespec* tsp = nullptr;
  if (timeout_ns >= 0) {
    ts.tv_sec = static_cast<time_t>(timeout_ns / 1'000'000'000);
    ts.tv_nsec = static_cast<long>(timeout_ns % 1'000'000'000);
    tsp = &ts;
  }
  const long rc = ::syscall(SYS_futex, word, op(FUTEX_WAIT, scope), expected, tsp, nullptr, 0);
  return rc == 0 ? 0 : -errno;
}

int futex_wake_all(const std::atomic<uint32_t>* word, FutexScope scope) {
  const long rc = ::syscall(SYS_futex, word, op(FUTEX_WAKE, scope), INT_MAX, nullptr, nullptr, 0);
  return rc >= 0 ? static_cast<int>(rc) : -errno;
}

}  // namespace ceilpose
