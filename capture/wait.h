#pragma once
// Blocking waits for the capture path, all on CLOCK_MONOTONIC: absolute sleeps
// (so pacing does not drift with wake-up latency) and a futex on a 32-bit
// counter (so a waiting thread costs nothing and a waker never blocks).
#include <atomic>
#include <cstdint>

namespace ceilpose::capture {

// Sleeps until CLOCK_MONOTONIC reaches deadline_ns (returns at once if past).
void sleep_until_ns(int64_t deadline_ns);

// Waits while *word == expected, at most timeout_ns (relative); returns early on
// futex_wake or a spurious wake-up, so callers re-check their condition.
void futex_wait(std::atomic<uint32_t>* word, uint32_t expected, int64_t timeout_ns);
// Wakes every waiter on word; never blocks.
void futex_wake_all(std::atomic<uint32_t>* word);

}  // namespace ceilpose::capture
