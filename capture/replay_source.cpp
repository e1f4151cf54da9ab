#include "capture/replay_source.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "capture/wait.h"
#include "core/clock.h"

namespace ceilpose::capture {

ReplaySource::ReplaySource(std::string dir, SourceOptions options)
    : dir_(std::move(dir)), options_(std::move(options)) {}

ReplaySource::~ReplaySource() = default;

std::string ReplaySource::describe() const {
  std::string text = "replay:" + dir_;
  if (!reader_) return text + " (not open)";
  char extra[160];
  const auto& k = reader_->camera().intrinsics;
  if (as_fast_as_possible()) {
    std::snprintf(extra, sizeof extra, " (%zu frames, %dx%d, as fast as possible%s)", frame_count(),
                  k.width, k.height, options_.replay_loop ? ", loop" : "");
  } else {
    std::snprintf(extra, sizeof extra, " (%zu frames, %dx%d, %.2fx real time%s)", frame_count(),
                  k.width, k.height, options_.replay_speed, options_.replay_loop ? ", loop" : "");
  }
  return text + extra;
}

Result<void> ReplaySource::do_open() {
  if (!(options_.replay_speed >= 0.0)) {
    return make_error("replay:" + dir_ +
                      ": replay speed must be >= 0 (0: as fast as possible), got " +
                      std::to_string(options_.replay_speed));
  }
  auto reader = RecordingReader::open(dir_);
  if (!reader) return reader.error();
  if (reader->rows().empty()) return make_error("replay:" + dir_ + ": the recording has no frames");
  reader_.emplace(std::move(reader).value());
  const auto& rows = reader_->rows();
  const auto& k = reader_->camera().intrinsics;
  pool_.resize(std::max(2, options_.buffer_count), k.width, k.height, PixelFormat::kRgb24);
  // A loop restarts one average frame interval after the last frame.
  const int64_t span_ns = rows.back().timestamp_ns - rows.front().timestamp_ns;
  const int64_t interval_ns = rows.size() > 1
                                  ? span_ns / static_cast<int64_t>(rows.size() - 1)
                                  : static_cast<int64_t>(1e9 / std::max(1.0, options_.fps));
  loop_period_ns_ = span_ns + interval_ns;
  return {};
}

Result<void> ReplaySource::do_start() {
  next_row_ = 0;
  loop_offset_ns_ = 0;
  start_ns_ = monotonic_ns();
  return {};
}

NextStatus ReplaySource::do_next(Frame* out, int timeout_ms) {
  const auto& rows = reader_->rows();
  if (next_row_ == rows.size()) {
    if (!options_.replay_loop) return NextStatus::kEndOfStream;
    next_row_ = 0;
    loop_offset_ns_ += loop_period_ns_;
  }
  const RecordingRow& row = rows[next_row_];
  const int64_t now_ns = monotonic_ns();
  int64_t due_ns = now_ns;
  if (!as_fast_as_possible()) {
    const double recorded_ns =
        static_cast<double>(row.timestamp_ns - rows.front().timestamp_ns + loop_offset_ns_);
    due_ns = start_ns_ + static_cast<int64_t>(std::llround(recorded_ns / options_.replay_speed));
    const int64_t deadline_ns = now_ns + static_cast<int64_t>(timeout_ms) * 1'000'000;
    if (due_ns > deadline_ns) {
      sleep_until_ns(deadline_ns);
      return NextStatus::kTimeout;
    }
    sleep_until_ns(due_ns);
  }
  int32_t slot = -1;
  Image* image = pool_.acquire(&slot);
  if (image == nullptr) {
    // Every slot is held downstream: a live replay drops this frame like a
    // camera with no free buffer would.
    ++stats_.drops;
    ++next_row_;
    return NextStatus::kTimeout;
  }
  if (auto r = reader_->load_frame(next_row_, image); !r) {
    pool_.release(slot);
    if (!reported_error_) {
      spdlog::error("replay:{}: {}", dir_, r.error().message);
      reported_error_ = true;
    }
    return NextStatus::kError;
  }
  Frame f;
  f.image = image->view();
  f.capture_ns = due_ns;
  f.dequeue_ns = monotonic_ns();
  f.source_timestamp_ns = row.timestamp_ns;
  f.source_index = row.index;
  f.sequence = sequence_++;
  f.has_ground_truth = row.has_ground_truth;
  f.ground_truth = row.ground_truth;
  f.buffer_index = slot;
  ++stats_.frames;
  ++next_row_;
  *out = f;
  return NextStatus::kFrame;
}

void ReplaySource::do_release(const Frame& frame) { pool_.release(frame.buffer_index); }

}  // namespace ceilpose::capture
