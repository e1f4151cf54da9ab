#pragma once
#include <cstdint>
#include <ctime>

namespace ceilpose {

inline constexpr int64_t kMsNs = 1'000'000;  // nanoseconds in a millisecond

inline int64_t clock_ns(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}
inline int64_t monotonic_ns() { return clock_ns(CLOCK_MONOTONIC); }
inline int64_t realtime_ns() { return clock_ns(CLOCK_REALTIME); }

}  // namespace ceilpose
