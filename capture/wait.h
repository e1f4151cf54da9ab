#pragma once
// Pacing for the capture path: absolute sleeps on CLOCK_MONOTONIC, so pacing
// does not drift with wake-up latency. (Futex waits: core/futex.h.)
#include <cstdint>

namespace ceilpose::capture {

// Sleeps until CLOCK_MONOTONIC reaches deadline_ns (returns at once if past).
void sleep_until_ns(int64_t deadline_ns);

}  // namespace ceilpose::capture
