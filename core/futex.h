#pragma once
// The one futex wrapper: wait while a 32-bit word holds a value, wake its
// waiters. Private futexes for threads of one process (the capture ring),
// shared ones for a word in memory mapped by several processes (the pose
// segment), where the kernel keys the word by its backing page.
#include <atomic>
#include <cstdint>

namespace ceilpose {

enum class FutexScope { kProcess, kShared };

static_assert(sizeof(std::atomic<uint32_t>) == sizeof(uint32_t) &&
                  std::atomic<uint32_t>::is_always_lock_free,
              "a futex word must be a plain lock-free 32-bit integer");

// Sleeps while *word == expected, at most timeout_ns (relative; < 0 waits
// without limit). The kernel compares and sleeps atomically, so a wake
// between the caller's check and this call is not lost. Returns 0 when woken
// (or spuriously), else -errno (-ETIMEDOUT, -EAGAIN when *word != expected,
// -EINTR); callers re-check their condition either way.
int futex_wait(const std::atomic<uint32_t>* word, uint32_t expected, int64_t timeout_ns,
               FutexScope scope);
// Wakes every waiter; never blocks. The number woken, or -errno.
int futex_wake_all(const std::atomic<uint32_t>* word, FutexScope scope);

}  // namespace ceilpose
