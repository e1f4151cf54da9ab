#include "capture/synthetic_source.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "capture/wait.h"
#include "core/clock.h"

namespace ceilpose::capture {

std::optional<PixelFormat> synthetic_pixel_format(const std::vector<PixelFormat>& wanted) {
  if (wanted == SourceOptions{}.pixel_formats) return PixelFormat::kRgb24;
  if (wanted.size() != 1 || wanted.front() == PixelFormat::kMjpeg) return std::nullopt;
  return wanted.front();
}

SyntheticSource::SyntheticSource(SourceOptions options, std::shared_ptr<FrameGenerator> generator)
    : options_(std::move(options)), generator_(std::move(generator)) {}

SyntheticSource::~SyntheticSource() = default;

std::string SyntheticSource::describe() const {
  const CameraIntrinsics& k = generator_->intrinsics();
  char text[160];
  std::snprintf(text, sizeof text, "synthetic %dx%d %s %.1f fps, %s", k.width, k.height,
                to_string(generator_->format()), options_.fps, generator_->describe().c_str());
  return text;
}

Result<void> SyntheticSource::do_open() {
  if (!(options_.fps > 0.0) || options_.fps > 10000.0) {
    return make_error("synthetic: frame rate must be in (0, 10000] fps, got " +
                      std::to_string(options_.fps));
  }
  const CameraIntrinsics& k = generator_->intrinsics();
  if (k.width <= 0 || k.height <= 0) {
    return make_error("synthetic: camera size must be positive, got " + std::to_string(k.width) +
                      "x" + std::to_string(k.height));
  }
  pool_.resize(std::max(2, options_.buffer_count), k.width, k.height, generator_->format());
  period_ns_ = static_cast<int64_t>(std::llround(1e9 / options_.fps));
  return {};
}

Result<void> SyntheticSource::do_start() {
  start_ns_ = monotonic_ns();
  tick_ = 0;
  return {};
}

NextStatus SyntheticSource::do_next(Frame* out, int timeout_ms) {
  const int64_t now_ns = monotonic_ns();
  int64_t due_ns = start_ns_ + static_cast<int64_t>(tick_) * period_ns_;
  if (now_ns - due_ns >= period_ns_) {
    // Behind by whole frames: those exposures never happened. Resume at the
    // next tick, as a camera would, not at the one that already passed: the
    // capture thread then sleeps between renders even when rendering is
    // slower than the frame rate, so a SCHED_FIFO capture thread cannot take
    // a core for good (it starved every SCHED_OTHER thread on the machine).
    const uint64_t next = static_cast<uint64_t>((now_ns - start_ns_) / period_ns_) + 1;
    stats_.drops += next - tick_;
    tick_ = next;
    due_ns = start_ns_ + static_cast<int64_t>(tick_) * period_ns_;
  }
  const int64_t deadline_ns = now_ns + static_cast<int64_t>(timeout_ms) * 1'000'000;
  if (due_ns > deadline_ns) {
    sleep_until_ns(deadline_ns);
    return NextStatus::kTimeout;
  }
  sleep_until_ns(due_ns);
  const uint64_t tick = tick_++;
  int32_t slot = -1;
  Image* image = pool_.acquire(&slot);
  if (image == nullptr) {
    ++stats_.drops;  // every slot held downstream, like a camera with no free buffer
    return NextStatus::kTimeout;
  }
  Pose2D pose;
  generator_->generate(due_ns - start_ns_, tick, image, &pose);
  Frame f;
  f.image = image->view();
  f.capture_ns = due_ns;
  f.dequeue_ns = monotonic_ns();
  f.source_timestamp_ns = due_ns;
  f.sequence = sequence_++;
  f.has_ground_truth = true;
  f.ground_truth = pose;
  f.buffer_index = slot;
  ++stats_.frames;
  *out = f;
  return NextStatus::kFrame;
}

void SyntheticSource::do_release(const Frame& frame) { pool_.release(frame.buffer_index); }

}  // namespace ceilpose::capture
