#pragma once
// One captured frame as it travels from a FrameSource, through the capture
// thread's ring, to the pipeline and back. Trivially copyable on purpose: the
// SPSC rings copy it by value, and the pixels stay where the source put them.
#include <cstdint>
#include <type_traits>

#include "core/image.h"
#include "core/pose.h"

namespace ceilpose::capture {

struct Frame {
  // Points into the source's buffer (a V4L2 mmap'd buffer for raw formats) and
  // stays valid until the frame is handed back with FrameSource::release().
  ImageView image;
  int64_t capture_ns = 0;           // CLOCK_MONOTONIC, driver/sensor time of the exposure
  int64_t dequeue_ns = 0;           // CLOCK_MONOTONIC, when the capture thread got it
  int64_t source_timestamp_ns = 0;  // the recording's timestamp for replay, else capture_ns
  int64_t source_index = -1;        // row of the recording for replay, else -1
  uint64_t sequence = 0;            // counts frames this source delivered, from 0
  bool has_ground_truth = false;
  Pose2D ground_truth;        // robot pose, when the source knows it (synthetic, replay)
  int32_t buffer_index = -1;  // the source's buffer slot, for release()
  uint32_t generation = 0;    // the source's buffer set (bumped on device reopen)
};
static_assert(std::is_trivially_copyable_v<Frame>, "Frames are copied through lock-free rings");

enum class NextStatus {
  kFrame,        // *out holds a frame; hand it back with release()
  kTimeout,      // nothing within timeout_ms (a live source may be recovering)
  kEndOfStream,  // a finite source (replay without loop) has delivered everything
  kError,        // unrecoverable; the source logged why
};

const char* to_string(NextStatus status);

// Counters a source keeps for status reports; read from the owning thread.
struct SourceStats {
  uint64_t frames = 0;      // delivered by next()
  uint64_t drops = 0;       // lost inside the source (driver sequence gaps, no free buffer)
  uint64_t outages = 0;     // times the device vanished, failed or stalled
  uint64_t reconnects = 0;  // successful reopen after an outage
  uint64_t corrupt = 0;     // frames discarded as undecodable (MJPEG) or flagged by the driver
};

}  // namespace ceilpose::capture
