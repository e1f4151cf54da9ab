#pragma once
// Replay of a SPEC §4 recording (replay:DIR) as if it were a camera: frames are
// released at their recorded timestamps (divided by a speed factor) on
// CLOCK_MONOTONIC, or as fast as the consumer takes them; optionally looped.
// Each frame carries the recording's timestamp, row index and ground truth.
//
// A frame that cannot be decoded is an error (kError, logged with the file and
// frames.csv line): a recording is never silently skipped through.
//
// Threads: see FrameSource; one thread (the capture thread) only.
#include <optional>
#include <string>

#include "capture/frame_pool.h"
#include "capture/frame_source.h"
#include "recording/recording_reader.h"

namespace ceilpose::capture {

class ReplaySource final : public FrameSource {
 public:
  // Stores the configuration; cannot fail.
  ReplaySource(std::string dir, SourceOptions options);
  ~ReplaySource() override;

  std::string describe() const override;
  SourceStats stats() const override { return stats_; }
  bool live() const override { return !as_fast_as_possible(); }
  int buffers() const override { return pool_.size(); }
  bool camera_intrinsics(CameraIntrinsics* out) const override {
    if (!reader_) return false;
    *out = reader_->camera().intrinsics;
    return true;
  }

  // Valid once open.
  size_t frame_count() const { return reader_ ? reader_->rows().size() : 0; }

 protected:
  bool as_fast_as_possible() const { return options_.replay_speed == 0.0; }
  Result<void> do_open() override;
  Result<void> do_start() override;
  NextStatus do_next(Frame* out, int timeout_ms) override;
  void do_release(const Frame& frame) override;
  void do_stop() override {}

 private:
  const std::string dir_;
  const SourceOptions options_;
  std::optional<RecordingReader> reader_;
  FramePool pool_;
  size_t next_row_ = 0;
  int64_t start_ns_ = 0;        // CLOCK_MONOTONIC time of the first frame
  int64_t loop_offset_ns_ = 0;  // recording time added per completed loop
  int64_t loop_period_ns_ = 0;  // one pass of the recording plus one frame interval
  uint64_t sequence_ = 0;
  bool reported_error_ = false;
  SourceStats stats_;
};

}  // namespace ceilpose::capture
