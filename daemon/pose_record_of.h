#pragma once
// A localized frame as the record both outputs carry: the shared-memory pose
// and the DDS state (the fleet) are the same bytes, made in one place.
#include <cstdint>

#include "ipc/shm/pose_record.h"
#include "pipeline/localization.h"

namespace ceilpose::daemon {

// `real_minus_mono_ns`: CLOCK_REALTIME minus CLOCK_MONOTONIC now, which turns
// the frame's mid-exposure time into capture_real_ns. seq and the publish
// times are left 0 for the writer.
PoseRecord pose_record_of(const Localization& loc, int64_t real_minus_mono_ns);

}  // namespace ceilpose::daemon
