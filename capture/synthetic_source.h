#pragma once
// The simulator as a live camera (synthetic): renders the SPEC ceiling as seen
// from a robot following sim::trajectory_pose, at options.fps, paced on
// CLOCK_MONOTONIC with absolute sleeps so the rate does not drift. Each frame
// carries its ground-truth pose. Image size and lens come from
// options.intrinsics; options.effects degrade the image.
//
// This is capture's one dependency on sim/: it calls sim::Renderer with a pose
// and knows nothing of markers.
//
// If rendering falls behind the frame rate, the ticks that passed are counted
// as drops (as a camera would lose them) and the next frame is the current one.
//
// Threads: see FrameSource; one thread (the capture thread) only.
#include <optional>

#include "capture/frame_pool.h"
#include "capture/frame_source.h"
#include "sim/renderer.h"

namespace ceilpose::capture {

class SyntheticSource final : public FrameSource {
 public:
  // Stores the configuration; cannot fail.
  explicit SyntheticSource(SourceOptions options);
  ~SyntheticSource() override;

  std::string describe() const override;
  SourceStats stats() const override { return stats_; }
  int buffers() const override { return pool_.size(); }
  bool camera_intrinsics(CameraIntrinsics* out) const override {
    *out = options_.intrinsics;
    return true;
  }

 protected:
  Result<void> do_open() override;
  Result<void> do_start() override;
  NextStatus do_next(Frame* out, int timeout_ms) override;
  void do_release(const Frame& frame) override;
  void do_stop() override {}

 private:
  const SourceOptions options_;
  std::optional<sim::Renderer> renderer_;
  FramePool pool_;
  int64_t period_ns_ = 0;
  int64_t start_ns_ = 0;
  uint64_t tick_ = 0;  // frame number on the camera's clock (includes dropped ticks)
  uint64_t sequence_ = 0;
  SourceStats stats_;
};

}  // namespace ceilpose::capture
