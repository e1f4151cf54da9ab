#include "daemon/pipeline_worker.h"

#include <pthread.h>
#include <sched.h>

#include <chrono>
#include <cmath>

#include "core/clock.h"
#ifdef CEILPOSE_DAEMON_HAVE_DDS
#include "ipc/dds/dds_pose_publisher.h"
#endif

namespace ceilpose::daemon {
namespace {

constexpr int kAcquireTimeoutMs = 50;  // bounds how late stop() and status are noticed

uint8_t client_mode(PositioningMode mode) { return static_cast<uint8_t>(mode); }

}  // namespace

PipelineWorker::PipelineWorker(const ServiceConfig& config, WorkerOptions options,
                               capture::CaptureThread* capture, ShmPoseWriter* shm,
                               DdsPosePublisher* dds, ProblemCounters* problems,
                               ProgressCounter* progress)
    : options_(options),
      capture_(capture),
      shm_(shm),
      dds_(dds),
      problems_(problems),
      progress_(progress),
      pipeline_(config.pipeline),
      mode_(config.positioning_mode),
      filter_enabled_(config.pipeline.filter.enabled),
      filter_(config.pipeline.filter) {}

PipelineWorker::~PipelineWorker() { stop(); }

void PipelineWorker::start() {
  thread_ = std::thread([this] { run(); });
  pthread_setname_np(thread_.native_handle(), "ceilpose-pipe");
  if (options_.rt_priority > 0) {
    // From here rather than the thread itself so that the result is known
    // (and logged by the caller) before the first frame.
    sched_param param{};
    param.sched_priority = options_.rt_priority;
    realtime_.store(pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &param) == 0,
                    std::memory_order_release);
  }
}

void PipelineWorker::stop() {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

void PipelineWorker::reload(const ServiceConfig& config, bool reset_filter) {
  std::lock_guard lock(pending_mutex_);
  pending_ = Pending{config.pipeline, config.positioning_mode, reset_filter};
  has_pending_.store(true, std::memory_order_release);
}

PoseSnapshot PipelineWorker::latest() const {
  std::lock_guard lock(snapshot_mutex_);
  return snapshot_;
}

void PipelineWorker::run() {
  status_ns_ = monotonic_ns();
  next_status_ns_ = status_ns_;
  while (!stop_.load(std::memory_order_acquire)) {
    if (has_pending_.load(std::memory_order_acquire)) apply_pending();
    capture::Frame frame;
    if (capture_->acquire_latest(&frame, kAcquireTimeoutMs)) {
      process(frame);
      capture_->release(frame);
      const uint64_t n = frames_.fetch_add(1, std::memory_order_relaxed) + 1;
      progress_->advance(monotonic_ns());
      if (options_.stall_after_frames != 0 && n >= options_.stall_after_frames) {
        stall_until_stopped();
        break;
      }
    } else if (capture_->finished()) {
      break;
    }
    const int64_t now = monotonic_ns();
    if (now >= next_status_ns_) publish_status(now);
  }
  publish_status(monotonic_ns());
  finished_.store(!stop_.load(std::memory_order_acquire), std::memory_order_release);
}

// Reload: not in the per-frame path, so set_config may rebuild tables.
void PipelineWorker::apply_pending() {
  std::unique_lock lock(pending_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;  // the control thread is writing; take it next frame
  if (!pending_) return;
  pipeline_.set_config(pending_->pipeline);
  mode_ = pending_->mode;
  filter_enabled_ = pending_->pipeline.filter.enabled;
  if (pending_->reset_filter) filter_ = TemporalFilter(pending_->pipeline.filter);
  pending_.reset();
  has_pending_.store(false, std::memory_order_release);
}

void PipelineWorker::process(const capture::Frame& frame) {
  capture::FrameStamps stamps;
  stamps.capture_ns = frame.capture_ns;
  stamps.dequeue_ns = frame.dequeue_ns;
  stamps.pipeline_start_ns = monotonic_ns();

  // 1. Localize the frame on its own.
  pipeline_.process(frame.image, mode_, &result_);
  const PoseEstimate& measured = result_.estimate;
  if (result_.marker_count == 0) {
    problems_->count(Problem::kNoMarkers);
  } else if (!measured.valid) {
    problems_->count(
        depth_scale_contradicts_heights(pipeline_.config().positioning, measured.depth_scale)
            ? Problem::kWrongHeights
            : Problem::kInvalidPose);
  }

  // 2. Filter over time (capture time, so pipeline jitter does not enter it).
  const PoseEstimate out = filter_enabled_ ? filter_.update(measured, frame.capture_ns) : measured;
  if (measured.valid) {
    had_fix_ = true;
    fix_ = FixState::kOk;
  } else {
    fix_ = out.valid ? FixState::kCoasting : (had_fix_ ? FixState::kLost : FixState::kNone);
  }

  // 3. Publish on shared memory (every frame, so readers see the daemon live
  //    even without a fix), then DDS (valid poses only).
  const int64_t real_minus_mono_ns = realtime_ns() - monotonic_ns();
  PoseRecord rec{};
  rec.capture_mono_ns = frame.capture_ns;
  rec.capture_real_ns = frame.capture_ns + real_minus_mono_ns;
  rec.x_m = out.pose.x_m;
  rec.y_m = out.pose.y_m;
  rec.yaw_rad = out.pose.yaw_rad;
  for (int i = 0; i < 9; ++i) rec.covariance[i] = out.covariance[i];
  rec.flags = (out.valid ? kPoseValid : 0u) | (filter_enabled_ ? kPoseFiltered : 0u) |
              (out.valid && !measured.valid ? kPoseCoasting : 0u);
  rec.mode = client_mode(out.mode);
  rec.markers = static_cast<uint16_t>(out.markers);
  shm_->publish(rec);
#ifdef CEILPOSE_DAEMON_HAVE_DDS
  if (dds_ != nullptr && out.valid) {
    DdsPose pose;
    pose.capture_realtime_ns = rec.capture_real_ns;
    pose.valid = true;
    pose.pose = out.pose;
    pose.covariance = out.covariance;
    if (!dds_->publish(pose)) problems_->count(Problem::kPublishFailed);
  }
#endif
  stamps.published_ns = monotonic_ns();
  if (frames_.load(std::memory_order_relaxed) >= options_.latency_warmup_frames)
    latency_.record(stamps);

  // 4. Hand the control thread a snapshot, unless it is reading right now.
  last_.seq = shm_->last_seq();
  last_.capture_ns = frame.capture_ns;
  last_.valid = out.valid;
  last_.pose = out.pose;
  last_.mode = out.mode;
  last_.markers = out.markers;
  last_.has_ground_truth = frame.has_ground_truth;
  last_.ground_truth = frame.ground_truth;
  last_.latency_ns = stamps.published_ns - stamps.dequeue_ns;
  last_.fix = fix_;
  last_.fps = fps_;
  std::unique_lock lock(snapshot_mutex_, std::try_to_lock);
  if (lock.owns_lock()) snapshot_ = last_;
}

void PipelineWorker::publish_status(int64_t now_ns) {
  const uint64_t frames = frames_.load(std::memory_order_relaxed);
  const double dt_s = static_cast<double>(now_ns - status_ns_) * 1e-9;
  if (dt_s > 0.0) fps_ = static_cast<double>(frames - frames_at_status_) / dt_s;
  frames_at_status_ = frames;
  status_ns_ = now_ns;
  next_status_ns_ = now_ns + int64_t{options_.status_interval_ms} * 1'000'000;

  const capture::CaptureStats cs = capture_->stats();
  const capture::LatencySummary lat = latency_.capture_to_published().summary();
  StatusRecord status{};
  status.fps = fps_;
  status.frames = cs.frames;
  status.drops = cs.drops + cs.source_drops;
  status.skipped = cs.skipped;
  status.outages = cs.outages;
  status.latency_p50_us = static_cast<uint32_t>(lat.p50_us);
  status.latency_p90_us = static_cast<uint32_t>(lat.p90_us);
  status.latency_p99_us = static_cast<uint32_t>(lat.p99_us);
  status.latency_max_us = static_cast<uint32_t>(lat.max_us);
  status.fix_state = static_cast<uint32_t>(fix_);
  set_status_source(&status, capture_->description().c_str());
  shm_->update_status(status);
#ifdef CEILPOSE_DAEMON_HAVE_DDS
  if (dds_ != nullptr) {
    DdsStatus ds;
    ds.publish_realtime_ns = realtime_ns();
    ds.health = capture_->failed()
                    ? DdsHealth::kFailed
                    : (fix_ == FixState::kOk ? DdsHealth::kOk : DdsHealth::kDegraded);
    ds.fix = fix_ == FixState::kOk || fix_ == FixState::kCoasting;
    ds.mode = client_mode(last_.mode);
    ds.markers = static_cast<uint16_t>(last_.markers);
    ds.fps = static_cast<float>(fps_);
    ds.frames = cs.frames;
    ds.drops = status.drops;
    ds.latency_p50_us = status.latency_p50_us;
    ds.latency_p90_us = status.latency_p90_us;
    ds.latency_p99_us = status.latency_p99_us;
    ds.latency_max_us = status.latency_max_us;
    if (!dds_->publish_status(ds)) problems_->count(Problem::kPublishFailed);
  }
#endif
  last_.fps = fps_;
  std::unique_lock lock(snapshot_mutex_, std::try_to_lock);
  if (lock.owns_lock()) snapshot_.fps = fps_;
}

void PipelineWorker::stall_until_stopped() {
  while (!stop_.load(std::memory_order_acquire))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

}  // namespace ceilpose::daemon
