#pragma once
// A synthetic live camera: asks its FrameGenerator (in ceilposed, the
// simulator) for each exposure at options.fps, paced on CLOCK_MONOTONIC with
// absolute sleeps so the rate does not drift. Each frame carries the
// generator's ground-truth pose; image size and lens are the generator's.
// capture knows frames only: nothing here knows what the image shows.
//
// If rendering falls behind the frame rate, the ticks that passed are counted
// as drops (as a camera would lose them) and the next frame is the next tick.
//
// Threads: see FrameSource. Rendering is the camera's work, not the capture
// thread's: a sensor thread of its own (normal priority, any CPU, whatever
// the thread that started it runs at) renders each exposure and leaves it
// for next(), as a camera's DMA leaves a buffer for VIDIOC_DQBUF. The
// capture thread then only waits and hands over, so the pipeline thread can
// share its CPU (capture.cpu): rendering in the capture thread took 85 % of
// that CPU at 60 fps and starved it (frame ready -> pose p99 0.3-0.5 s).
// A rendered frame next() has not taken when the next one is ready is
// released and counted as a drop.
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "capture/frame_pool.h"
#include "capture/frame_source.h"
#include "core/frame_generator.h"

namespace ceilpose::capture {

// The format the synthetic camera hands its frames over in, for the
// configured capture.pixel_format list: one format a camera's ISP gives
// (YUYV, NV12, YUV420, RGB24, BGR24, GRAY8) as is, so that the daemon runs
// the frame path of a USB or Pi camera; the default list ("auto") RGB24;
// MJPEG nothing (there is no encoder on the camera's side here).
std::optional<PixelFormat> synthetic_pixel_format(const std::vector<PixelFormat>& wanted);

class SyntheticSource final : public FrameSource {
 public:
  // Stores the configuration; cannot fail.
  SyntheticSource(SourceOptions options, std::shared_ptr<FrameGenerator> generator);
  ~SyntheticSource() override;

  std::string describe() const override;
  SourceStats stats() const override {
    std::lock_guard lock(mutex_);
    return stats_;
  }
  int buffers() const override { return pool_.size(); }
  bool camera_intrinsics(CameraIntrinsics* out) const override {
    *out = generator_->intrinsics();
    return true;
  }

 protected:
  Result<void> do_open() override;
  Result<void> do_start() override;
  NextStatus do_next(Frame* out, int timeout_ms) override;
  void do_release(const Frame& frame) override;
  void do_stop() override { stop_sensor(); }

 private:
  void sense();  // the sensor thread
  void stop_sensor();

  const SourceOptions options_;
  const std::shared_ptr<FrameGenerator> generator_;
  int64_t period_ns_ = 0;
  int64_t start_ns_ = 0;
  // The sensor thread's alone.
  uint64_t tick_ = 0;  // frame number on the camera's clock (includes dropped ticks)
  uint64_t sequence_ = 0;
  std::thread sensor_;

  mutable std::mutex mutex_;  // guards what follows
  std::condition_variable ready_cv_;
  FramePool pool_;              // slots acquired by the sensor, released by next()'s caller
  std::optional<Frame> ready_;  // the newest rendered frame next() has not taken
  bool stopping_ = false;
  SourceStats stats_;
};

}  // namespace ceilpose::capture
