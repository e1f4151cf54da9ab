#include "capture/exposure_timing.h"

#include <time.h>

namespace ceilpose::capture {
namespace {

int64_t read_ns(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

int64_t boottime_minus_monotonic_ns() {
  // Monotonic on both sides of the boot-time read: the pair brackets it, and
  // their mean cancels the reads' own duration.
  const int64_t m0 = read_ns(CLOCK_MONOTONIC);
  const int64_t b = read_ns(CLOCK_BOOTTIME);
  const int64_t m1 = read_ns(CLOCK_MONOTONIC);
  return b - (m0 + (m1 - m0) / 2);
}

}  // namespace ceilpose::capture
