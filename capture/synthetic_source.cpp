#include "capture/synthetic_source.h"

#include <pthread.h>
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "core/clock.h"

namespace ceilpose::capture {

std::optional<PixelFormat> synthetic_pixel_format(const std::vector<PixelFormat>& wanted) {
  if (wanted == SourceOptions{}.pixel_formats) return PixelFormat::kRgb24;
  if (wanted.size() != 1 || wanted.front() == PixelFormat::kMjpeg) return std::nullopt;
  return wanted.front();
}

SyntheticSource::SyntheticSource(SourceOptions options, std::shared_ptr<FrameGenerator> generator)
    : options_(std::move(options)), generator_(std::move(generator)) {}

SyntheticSource::~SyntheticSource() { stop_sensor(); }

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
  stop_sensor();
  start_ns_ = monotonic_ns();
  tick_ = 0;
  {
    std::lock_guard lock(mutex_);
    stopping_ = false;
  }
  sensor_ = std::thread([this] { sense(); });
  return {};
}

void SyntheticSource::stop_sensor() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  ready_cv_.notify_all();
  if (sensor_.joinable()) sensor_.join();
  std::lock_guard lock(mutex_);
  if (ready_) pool_.release(ready_->buffer_index);
  ready_.reset();
}

void SyntheticSource::sense() {
  // Started from the capture thread, this thread inherited its SCHED_FIFO
  // priority and CPU; a camera's sensor is neither.
  sched_param normal{};
  (void)pthread_setschedparam(pthread_self(), SCHED_OTHER, &normal);
  cpu_set_t process_cpus;
  if (sched_getaffinity(getpid(), sizeof process_cpus, &process_cpus) == 0)
    (void)sched_setaffinity(0, sizeof process_cpus, &process_cpus);
  pthread_setname_np(pthread_self(), "ceilpose-sensor");
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    const int64_t now_ns = monotonic_ns();
    int64_t due_ns = start_ns_ + static_cast<int64_t>(tick_) * period_ns_;
    if (now_ns - due_ns >= period_ns_) {
      // Behind by whole frames: those exposures never happened. Resume at
      // the next tick, as a camera would, not at the one that already passed.
      const uint64_t next = static_cast<uint64_t>((now_ns - start_ns_) / period_ns_) + 1;
      stats_.drops += next - tick_;
      tick_ = next;
      due_ns = start_ns_ + static_cast<int64_t>(tick_) * period_ns_;
    }
    // steady_clock is CLOCK_MONOTONIC, the clock of due_ns.
    const auto due = std::chrono::steady_clock::time_point(std::chrono::nanoseconds(due_ns));
    if (ready_cv_.wait_until(lock, due, [&] { return stopping_; })) break;
    const uint64_t tick = tick_++;
    int32_t slot = -1;
    Image* image = pool_.acquire(&slot);
    if (image == nullptr) {
      ++stats_.drops;  // every slot held downstream, like a camera with no free buffer
      continue;
    }
    lock.unlock();
    Pose2D pose;
    generator_->generate(due_ns - start_ns_, tick, image, &pose);
    Frame f;
    f.image = image->view();
    f.capture_ns = due_ns;
    f.source_timestamp_ns = due_ns;
    f.sequence = sequence_++;
    f.has_ground_truth = true;
    f.ground_truth = pose;
    f.buffer_index = slot;
    lock.lock();
    if (ready_) {
      pool_.release(ready_->buffer_index);  // never taken: superseded, as a camera's
      ++stats_.drops;
    }
    ready_ = f;
    lock.unlock();
    ready_cv_.notify_one();
    lock.lock();
  }
}

NextStatus SyntheticSource::do_next(Frame* out, int timeout_ms) {
  std::unique_lock lock(mutex_);
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(std::max(0, timeout_ms));
  if (!ready_cv_.wait_until(lock, deadline, [&] { return ready_.has_value() || stopping_; }) ||
      !ready_)
    return NextStatus::kTimeout;
  *out = *ready_;
  ready_.reset();
  out->dequeue_ns = monotonic_ns();
  ++stats_.frames;
  return NextStatus::kFrame;
}

void SyntheticSource::do_release(const Frame& frame) {
  std::lock_guard lock(mutex_);
  pool_.release(frame.buffer_index);
}

}  // namespace ceilpose::capture
