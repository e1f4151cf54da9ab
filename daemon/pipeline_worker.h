#pragma once
// The pipeline thread of ceilposed: CaptureThread -> Localizer -> sinks
// (shared memory, DDS). Takes the newest frame, localizes it, hands the
// Localization to every sink and stamps the frame's latency. It is also the
// single writer of the sinks while it runs (shared memory and DDS writers
// require one thread), so it publishes their status records too, each at the
// sink's own period.
//
// Per frame: no allocation, no exception, no logging; refusals are counted by
// the Localizer and progress in ProgressCounter (the watchdog's evidence).
//
// Threads: constructor, start(), stop(), reload() and the accessors from the
// control thread; everything else runs on the worker's own thread.
#include <pthread.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <thread>
#include <vector>

#include "capture/capture_thread.h"
#include "capture/latency_histogram.h"
#include "config/service_config.h"
#include "core/fix_state.h"
#include "daemon/publishing_sink.h"
#include "daemon/watchdog_gate.h"
#include "pipeline/localizer.h"

namespace ceilpose::daemon {

// The latest published pose as the control thread sees it (--print-poses,
// STATUS=). Trivially copyable.
struct PoseSnapshot {
  uint64_t frame = 0;  // frames localized so far; 0 = none yet
  int64_t capture_ns = 0;
  bool valid = false;
  Pose2D pose;
  PositioningMode mode = PositioningMode::kAuto;
  int markers = 0;
  Refusal refusal = Refusal::kNone;  // why the frame gave no measurement
  bool has_ground_truth = false;
  Pose2D ground_truth;
  int64_t latency_ns = 0;  // frame dequeued -> pose published
  FixState fix = FixState::kNone;
  double fps = 0.0;
};

struct WorkerOptions {
  int rt_priority = 0;  // SCHED_FIFO priority of the thread; 0 = normal scheduling
  // Pin the thread to this CPU; -1 = any. ceilposed gives it the capture
  // thread's (capture.cpu): a frame handed over on a busy CPU wakes no idle
  // one, whose wake-up under a hypervisor took 0.3-2.2 ms at p99
  // (docs/latency.md).
  int cpu = -1;
  // Frames whose latency is not recorded: the first ones after start touch
  // the pipeline's buffers for the first time (benchmarks skip them).
  uint64_t latency_warmup_frames = 0;
};

class PipelineWorker {
 public:
  // `sinks` are used from the worker's thread only while it runs.
  PipelineWorker(const ServiceConfig& config, WorkerOptions options,
                 capture::CaptureThread* capture, std::span<PublishingSink* const> sinks,
                 ProgressCounter* progress);
  ~PipelineWorker();
  PipelineWorker(const PipelineWorker&) = delete;
  PipelineWorker& operator=(const PipelineWorker&) = delete;

  void start();
  // Asks the thread to finish its frame and joins it.
  void stop();
  // CPU time the thread has used, nanoseconds (0 unless it runs); called
  // from the thread that starts and stops it.
  int64_t thread_cpu_ns() const;

  // Hands the live part of `config` (pipeline tuning, positioning mode,
  // filter) to the thread, which applies it between two frames.
  void reload(const ServiceConfig& config, bool reset_filter);

  // The thread left because the source ended or failed.
  bool finished() const { return finished_.load(std::memory_order_acquire); }
  PoseSnapshot latest() const;
  const capture::FrameLatency& latency() const { return latency_; }
  uint64_t frames() const { return frames_.load(std::memory_order_relaxed); }
  // Whether the thread got SCHED_FIFO (valid after start()).
  bool realtime() const { return realtime_.load(std::memory_order_acquire); }
  // Whether the thread was pinned to WorkerOptions::cpu, and why not: 0, or
  // pthread_setaffinity_np's error (valid after start()).
  bool pinned() const { return options_.cpu >= 0 && pin_error() == 0; }
  int pin_error() const { return pin_error_.load(std::memory_order_acquire); }
  // Frames per refusal since start (any thread).
  const RefusalHistogram& refusals() const { return localizer_.refusals(); }
  // Frames tracked and swept whole, by reason: read after stop().
  const SweepCounts& sweeps() const { return localizer_.sweeps(); }

 private:
  struct Pending {
    PipelineConfig pipeline;
    bool reset_filter;
  };

  void run();
  void apply_pending();
  void process(const capture::Frame& frame);
  void publish_status(int64_t now_ns, bool all);
  void update_fps(int64_t now_ns);

  const WorkerOptions options_;
  capture::CaptureThread* capture_;
  const std::vector<PublishingSink*> sinks_;
  ProgressCounter* progress_;

  // Pipeline-thread state.
  Localizer localizer_;
  std::vector<int64_t> next_status_ns_;  // per sink
  uint64_t frames_at_fps_ = 0;
  int64_t fps_ns_ = 0;
  double fps_ = 0.0;
  PoseSnapshot last_;
  int64_t last_frame_mono_ns_ = 0;  // when the last frame's pose was published
  const int64_t fix_lost_after_ns_;

  capture::FrameLatency latency_;
  std::atomic<uint64_t> frames_{0};
  std::atomic<bool> stop_{false};
  std::atomic<bool> finished_{false};
  std::atomic<bool> realtime_{false};
  std::atomic<int> pin_error_{0};
  std::atomic<bool> configured_{false};  // start() has set the thread's priority and CPU
  std::thread thread_;
  pthread_t native_thread_{};  // thread_'s, for its CPU clock from other threads

  mutable std::mutex snapshot_mutex_;  // writer only try_locks: never waits
  PoseSnapshot snapshot_;

  std::mutex pending_mutex_;
  std::atomic<bool> has_pending_{false};
  std::optional<Pending> pending_;
};

}  // namespace ceilpose::daemon
