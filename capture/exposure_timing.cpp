#include "capture/exposure_timing.h"

#include <time.h>

#include <cstdint>

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
  // their mean cancels the reads' own duration. A preemption inside one
  // bracket puts the boot-time read anywhere in it (16 us off was seen under
  // ASan on a loaded machine), so the tightest of a few brackets is kept.
  constexpr int kBrackets = 5;
  int64_t best_width_ns = INT64_MAX;
  int64_t best_offset_ns = 0;
  for (int k = 0; k < kBrackets; ++k) {
    const int64_t m0 = read_ns(CLOCK_MONOTONIC);
    const int64_t b = read_ns(CLOCK_BOOTTIME);
    const int64_t m1 = read_ns(CLOCK_MONOTONIC);
    if (m1 - m0 < best_width_ns) {
      best_width_ns = m1 - m0;
      best_offset_ns = b - (m0 + (m1 - m0) / 2);
    }
  }
  return best_offset_ns;
}

}  // namespace ceilpose::capture
