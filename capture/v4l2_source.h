#pragma once
// V4L2 camera (v4l2:/dev/videoN): mmap streaming, format negotiation, locked
// exposure/gain/white balance, driver timestamps on CLOCK_MONOTONIC moved to
// the centre row's mid-exposure (start-of-exposure or end-of-frame stamps,
// exposure_absolute, camera.readout_ms), and recovery from a device that vanishes, errors or
// stalls.
//
// Zero-copy for raw formats (YUYV, RGB24, BGR24, GREY): a frame's image points
// into the mmap'd driver buffer, which is re-queued only on release(). MJPEG is
// decoded on the capture thread into an RGB24 image kept per buffer (allocated
// at start(), never per frame), so the pipeline never sees compressed data.
//
// Recovery: ENODEV/EIO/any other dequeue or queue error, an error from poll,
// or no frame for stall_timeout_ms is an *outage*: the source stops streaming,
// closes the device, and inside later next() calls reopens it with a bounded
// exponential back-off, renegotiates and resumes. next() always returns within
// its timeout (kTimeout while recovering). Buffers the pipeline still holds
// across an outage stay mapped until they are released.
//
// Threads: see FrameSource; one thread (the capture thread) only.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "capture/exposure_timing.h"
#include "capture/frame_source.h"
#include "capture/v4l2_syscalls.h"
#include "codec/jpeg_codec.h"

namespace ceilpose::capture {

class V4l2Source final : public FrameSource {
 public:
  // Stores the configuration; cannot fail. `sys` must outlive the source.
  V4l2Source(std::string device_path, SourceOptions options,
             V4l2Syscalls* sys = &real_v4l2_syscalls());
  ~V4l2Source() override;

  std::string describe() const override;
  SourceStats stats() const override { return stats_; }
  int buffers() const override {
    return buffers_.empty() ? options_.buffer_count : static_cast<int>(buffers_.size());
  }

  // What open() negotiated (valid once open).
  PixelFormat negotiated_format() const { return format_; }
  int width() const { return width_; }
  int height() const { return height_; }
  double fps() const { return fps_; }
  // Whether the driver stamps buffers on CLOCK_MONOTONIC (else dequeue time is used).
  bool driver_timestamps() const { return driver_timestamps_; }

 protected:
  Result<void> do_open() override;
  Result<void> do_start() override;
  NextStatus do_next(Frame* out, int timeout_ms) override;
  void do_release(const Frame& frame) override;
  void do_stop() override;

 private:
  struct Buffer {
    void* start = nullptr;
    size_t length = 0;
    bool with_pipeline = false;  // handed out by next(), not yet released
  };
  struct RetiredBuffer {  // from a buffer set torn down while the pipeline held it
    uint32_t generation;
    int32_t index;
    void* start;
    size_t length;
  };

  Result<void> open_device();
  Result<void> query_capabilities();
  Result<void> negotiate_format();
  void set_frame_rate();
  void lock_controls();
  Result<void> start_streaming();
  void stop_streaming();
  void teardown_buffers();
  void begin_outage(const char* what, int error);
  bool try_reconnect();
  bool queue_buffer(int32_t index);
  NextStatus dequeue(Frame* out);

  const std::string path_;
  const SourceOptions options_;
  V4l2Syscalls* const sys_;

  UniqueFd fd_;
  PixelFormat format_ = PixelFormat::kYuyv;
  uint32_t fourcc_ = 0;
  int width_ = 0;
  int height_ = 0;
  int stride_bytes_ = 0;
  double fps_ = 0.0;
  bool driver_timestamps_ = true;
  bool warned_timestamps_ = false;
  // Mid-exposure stamps (capture/exposure_timing.h).
  static constexpr uint32_t kExposureRefreshFrames = 30;
  int64_t exposure_ns();
  const int64_t readout_ns_ = std::llround(options_.readout_ms * 1e6);
  StampEvent stamp_event_ = StampEvent::kEndOfFrame;
  int64_t exposure_ns_ = 0;
  uint32_t frames_since_exposure_read_ = 0;
  bool warned_exposure_ = false;
  bool reported_controls_ = false;

  std::vector<Buffer> buffers_;
  std::vector<Image> decoded_;  // MJPEG only, one RGB24 image per buffer
  codec::JpegCodec jpeg_;       // MJPEG only
  std::vector<RetiredBuffer> retired_;
  uint32_t generation_ = 0;
  bool streaming_ = false;

  bool recovering_ = false;
  int64_t outage_start_ns_ = 0;
  int64_t next_attempt_ns_ = 0;
  int backoff_ms_ = 0;
  int64_t last_frame_ns_ = 0;
  bool have_sequence_ = false;
  uint32_t last_driver_sequence_ = 0;
  uint64_t sequence_ = 0;
  SourceStats stats_;
};

}  // namespace ceilpose::capture
