#pragma once
// Every thread ceilposed starts, and every thread its libraries start (Cyclone
// DDS, spdlog), gets a stack of kThreadStackBytes instead of glibc's 8 MiB
// default: the capture thread's mlockall(MCL_FUTURE) makes each stack resident
// in full, and ~13 threads x 8 MiB was most of the daemon's 318 MB RSS
// (issue 30, docs/service.md "Memory").
#include <cstddef>

#include "core/result.h"

namespace ceilpose::daemon {

// The deepest stack measured under ceilposed's own threads is far below
// this (docs/service.md); libraries' threads are event loops.
inline constexpr size_t kThreadStackBytes = size_t{1} << 20;

// Sets the process-wide default for threads created afterwards; call before
// any thread starts.
Result<void> limit_thread_stacks();

}  // namespace ceilpose::daemon
