#pragma once
// A frame's time is the middle of its exposure, on CLOCK_MONOTONIC, for the
// centre row (SPEC §3): the instant the pose of record is of. Drivers stamp
// other events: V4L2 the start of exposure or the end of the frame, libcamera
// the first row on CLOCK_BOOTTIME. These turn a stamp into that instant;
// docs/latency.md tabulates them per backend.
#include <cstdint>

namespace ceilpose::capture {

enum class StampEvent {
  kStartOfExposure,  // the first row starts to expose (V4L2_BUF_FLAG_TSTAMP_SRC_SOE)
  kStartOfFrame,     // the first row is read out (libcamera's SensorTimestamp)
  kEndOfFrame,       // the last row is read out (V4L2_BUF_FLAG_TSTAMP_SRC_EOF, dequeue)
};

// The centre row's mid-exposure instant for a stamp of `event`, given the
// exposure time and the rolling-shutter readout (first row to last; 0 for a
// global shutter), nanoseconds.
constexpr int64_t exposure_mid_ns(int64_t stamp_ns, StampEvent event, int64_t exposure_ns,
                                  int64_t readout_ns) {
  switch (event) {
    case StampEvent::kStartOfExposure:
      return stamp_ns + exposure_ns / 2 + readout_ns / 2;
    case StampEvent::kStartOfFrame:
      return stamp_ns - exposure_ns / 2 + readout_ns / 2;
    case StampEvent::kEndOfFrame:
      return stamp_ns - exposure_ns / 2 - readout_ns / 2;
  }
  return stamp_ns;
}

// CLOCK_BOOTTIME minus CLOCK_MONOTONIC now (the time spent suspended), read
// as a pair so a stamp on CLOCK_BOOTTIME can be moved to CLOCK_MONOTONIC.
int64_t boottime_minus_monotonic_ns();

}  // namespace ceilpose::capture
