#pragma once
// Pinning a thread to one CPU, for the frame path's threads (capture and
// pipeline), which share one so that a frame's hand-over wakes no idle CPU.
#include <pthread.h>

namespace ceilpose {

// Pins `thread` to CPU `cpu` (>= 0). Returns 0, or the errno-style code of
// pthread_setaffinity_np (EINVAL: no such CPU in the process's allowed set).
int pin_thread_to_cpu(pthread_t thread, int cpu);

}  // namespace ceilpose
