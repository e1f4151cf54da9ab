#include "capture/wait.h"

#include <cerrno>
#include <ctime>

namespace ceilpose::capture {

void sleep_until_ns(int64_t deadline_ns) {
  if (deadline_ns <= 0) return;
  timespec ts{static_cast<time_t>(deadline_ns / 1'000'000'000),
              static_cast<long>(deadline_ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace ceilpose::capture
