#include "daemon/pipeline_worker.h"

#include <pthread.h>
#include <sched.h>

#include <chrono>
#include <cmath>

#include "core/clock.h"
#include "core/thread_affinity.h"

namespace ceilpose::daemon {
namespace {

constexpr int kAcquireTimeoutMs = 50;  // bounds how late stop() and status are noticed
// fps over windows no shorter than this, so that two sinks' status ticks close
// together do not give a rate from a handful of frames.
constexpr int64_t kMinFpsWindowNs = 200'000'000;

}  // namespace

PipelineWorker::PipelineWorker(const ServiceConfig& config, WorkerOptions options,
                               capture::CaptureThread* capture,
                               std::span<PublishingSink* const> sinks, ProgressCounter* progress)
    : options_(options),
      capture_(capture),
      sinks_(sinks.begin(), sinks.end()),
      progress_(progress),
      localizer_(config.pipeline),
      next_status_ns_(sinks.size(), 0),
      fix_lost_after_ns_(int64_t{config.ipc.stale_after_ms} * 1'000'000) {
  // Frame ready -> pose published without the scheduled whole sweep (process).
  localizer_.defer_scheduled_sweeps(true);
}

PipelineWorker::~PipelineWorker() { stop(); }

int64_t PipelineWorker::thread_cpu_ns() const {
  clockid_t clock{};
  timespec ts{};
  if (!thread_.joinable() || pthread_getcpuclockid(native_thread_, &clock) != 0 ||
      clock_gettime(clock, &ts) != 0)
    return 0;
  return int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

void PipelineWorker::start() {
  thread_ = std::thread([this] { run(); });
  native_thread_ = thread_.native_handle();
  pthread_setname_np(thread_.native_handle(), "ceilpose-pipe");
  // From here rather than the thread itself so that the result is known
  // (and logged by the caller) when start() returns; the thread takes its
  // first frame only once its priority and CPU are set (configured_).
  if (options_.rt_priority > 0) {
    sched_param param{};
    param.sched_priority = options_.rt_priority;
    realtime_.store(pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &param) == 0,
                    std::memory_order_release);
  }
  if (options_.cpu >= 0)
    pin_error_.store(pin_thread_to_cpu(thread_.native_handle(), options_.cpu),
                     std::memory_order_release);
  configured_.store(true, std::memory_order_release);
  configured_.notify_one();
}

void PipelineWorker::stop() {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

void PipelineWorker::reload(const ServiceConfig& config, bool reset_filter) {
  std::lock_guard lock(pending_mutex_);
  pending_ = Pending{config.pipeline, reset_filter};
  has_pending_.store(true, std::memory_order_release);
}

PoseSnapshot PipelineWorker::latest() const {
  std::lock_guard lock(snapshot_mutex_);
  return snapshot_;
}

void PipelineWorker::run() {
  configured_.wait(false, std::memory_order_acquire);
  fps_ns_ = monotonic_ns();
  while (!stop_.load(std::memory_order_acquire)) {
    if (has_pending_.load(std::memory_order_acquire)) apply_pending();
    capture::Frame frame;
    if (capture_->acquire_latest(&frame, kAcquireTimeoutMs)) {
      process(frame);
      capture_->release(frame);
      frames_.fetch_add(1, std::memory_order_relaxed);
      progress_->advance(monotonic_ns());
    } else if (capture_->finished()) {
      break;
    }
    publish_status(monotonic_ns(), false);
  }
  publish_status(monotonic_ns(), true);
  finished_.store(!stop_.load(std::memory_order_acquire), std::memory_order_release);
}

// Reload: not in the per-frame path, so the localizer may rebuild tables.
void PipelineWorker::apply_pending() {
  std::unique_lock lock(pending_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;  // the control thread is writing; take it next frame
  if (!pending_) return;
  localizer_.reconfigure(pending_->pipeline, pending_->reset_filter);
  pending_.reset();
  has_pending_.store(false, std::memory_order_release);
}

void PipelineWorker::process(const capture::Frame& frame) {
  capture::FrameStamps stamps;
  stamps.capture_ns = frame.capture_ns;
  stamps.dequeue_ns = frame.dequeue_ns;
  stamps.pipeline_start_ns = monotonic_ns();

  FrameInfo info;
  info.timestamp_ns = frame.capture_ns;  // capture time: pipeline jitter stays out of the filter
  info.index = frame.source_index;
  info.has_ground_truth = frame.has_ground_truth;
  info.ground_truth = frame.ground_truth;
  const Localization& loc = localizer_.localize(frame.image, info);
  for (PublishingSink* sink : sinks_) sink->consume(loc);

  stamps.published_ns = monotonic_ns();
  last_frame_mono_ns_ = stamps.published_ns;
  if (frames_.load(std::memory_order_relaxed) >= options_.latency_warmup_frames)
    latency_.record(stamps);

  // Hand the control thread a snapshot, unless it is reading right now.
  const PoseEstimate& out = loc.published;
  last_.frame = frames_.load(std::memory_order_relaxed) + 1;
  last_.capture_ns = frame.capture_ns;
  last_.valid = out.valid;
  last_.pose = out.pose;
  last_.mode = out.mode;
  last_.markers = out.markers;
  last_.refusal = loc.refusal;
  last_.has_ground_truth = frame.has_ground_truth;
  last_.ground_truth = frame.ground_truth;
  last_.latency_ns = stamps.published_ns - stamps.dequeue_ns;
  last_.fix = loc.fix;
  last_.fps = fps_;
  {
    std::unique_lock lock(snapshot_mutex_, std::try_to_lock);
    if (lock.owns_lock()) snapshot_ = last_;
  }
  // The scheduled whole sweep, now that the pose is out.
  localizer_.check_scheduled(frame.image);
}

void PipelineWorker::update_fps(int64_t now_ns) {
  if (now_ns - fps_ns_ < kMinFpsWindowNs) return;
  const uint64_t frames = frames_.load(std::memory_order_relaxed);
  fps_ =
      static_cast<double>(frames - frames_at_fps_) / (static_cast<double>(now_ns - fps_ns_) * 1e-9);
  frames_at_fps_ = frames;
  fps_ns_ = now_ns;
}

// Each sink at its own period; `all` (the thread leaving) publishes to every
// sink so the final counts are not lost.
void PipelineWorker::publish_status(int64_t now_ns, bool all) {
  bool due = all;
  for (int64_t next : next_status_ns_) due = due || now_ns >= next;
  if (!due) return;
  update_fps(now_ns);
  ServiceStatus status;
  status.now_ns = now_ns;
  status.fps = fps_;
  status.capture = capture_->stats();
  status.latency = latency_.capture_to_published().summary();
  status.source_failed = capture_->failed();
  status.source = capture_->description().c_str();
  // The fix of the last frame, unless no frame has come for longer than a
  // pose counts as fresh (ipc.stale_after_ms, what `ceilposectl pose`
  // judges by): then it is lost, not "fix" (issue 28 #22: a replay's 1 h
  // gap left status saying "fix" while pose said stale).
  status.fix = last_.fix;
  if ((status.fix == FixState::kOk || status.fix == FixState::kCoasting) &&
      now_ns - last_frame_mono_ns_ > fix_lost_after_ns_)
    status.fix = FixState::kLost;
  status.mode = last_.mode;
  status.markers = last_.markers;
  status.refusals = localizer_.refusals().snapshot();
  status.sweeps = localizer_.sweeps();
  for (size_t i = 0; i < sinks_.size(); ++i) {
    if (!all && now_ns < next_status_ns_[i]) continue;
    next_status_ns_[i] = now_ns + sinks_[i]->status_period_ns();
    sinks_[i]->publish_status(status);
  }
  last_.fps = fps_;
  std::unique_lock lock(snapshot_mutex_, std::try_to_lock);
  if (lock.owns_lock()) snapshot_.fps = fps_;
}

}  // namespace ceilpose::daemon
