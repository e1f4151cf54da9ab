#include "core/thread_affinity.h"

#include <sched.h>

#include <cerrno>

namespace ceilpose {

int pin_thread_to_cpu(pthread_t thread, int cpu) {
  if (cpu < 0 || cpu >= CPU_SETSIZE) return EINVAL;
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return pthread_setaffinity_np(thread, sizeof set, &set);
}

}  // namespace ceilpose
