#pragma once
// CaptureThread: runs one FrameSource on its own real-time thread and hands
// frames to the pipeline thread with latest-frame semantics.
//
//   capture thread                           pipeline thread
//   source.next() ──▶ ring `ready_` ──────▶ acquire_latest()  (newest; older
//        ▲                                        │             ones skipped)
//   source.release() ◀── ring `returned_` ◀── release()
//
// Both rings are SPSC and lock-free; only the capture thread touches the
// source, so only it re-queues V4L2 buffers (zero-copy: the pipeline reads the
// driver's buffer in place). The capture thread never blocks or spins on the
// pipeline: it keeps at most `in-flight budget` frames (source buffers minus
// one, so the driver always has a buffer to fill) outside the source; a frame
// that arrives while the budget is used up is handed straight back to the
// source and counted as a drop ("drop newest": the only choice an SPSC
// producer has, and the frames already waiting are at most one pipeline stall
// old). The pipeline always takes the newest waiting frame and returns the
// older ones, counted as skipped, so it never works through a backlog.
//
// A source that is not live (replay as fast as possible) is lossless instead:
// the capture thread waits for a returned frame rather than drop, and the
// pipeline gets frames in order without skipping.
//
// Threads: constructor, start(), stop(), the destructor from the owning
// (control) thread; acquire_latest() and release() from ONE consumer thread;
// stats()/realtime()/finished() from any thread.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "capture/frame_source.h"
#include "capture/spsc_ring.h"
#include "core/result.h"

namespace ceilpose::capture {

struct CaptureThreadOptions {
  int realtime_priority = 50;  // SCHED_FIFO 1..99; 0 leaves the thread SCHED_OTHER
  int cpu = -1;                // pin the capture thread to this CPU; -1 = no pinning
  bool lock_memory = true;     // mlockall(MCL_CURRENT|MCL_FUTURE): no page faults mid-frame
  // How long one source.next() may wait; bounds how late a released frame is
  // re-queued and how fast stop() is noticed.
  int next_timeout_ms = 20;
};

// What the thread actually got (the process may lack the privilege).
struct RealtimeStatus {
  bool fifo = false;
  int priority = 0;
  bool pinned = false;
  bool memory_locked = false;
};

struct CaptureStats {
  uint64_t frames = 0;   // handed to the ring
  uint64_t drops = 0;    // handed back at once: pipeline held the whole in-flight budget
  uint64_t skipped = 0;  // taken from the ring but superseded by a newer frame
  uint64_t source_drops = 0;
  uint64_t outages = 0;
  uint64_t reconnects = 0;
  uint64_t corrupt = 0;
};

class CaptureThread {
 public:
  static constexpr size_t kRingCapacity = 16;

  CaptureThread(std::unique_ptr<FrameSource> source, CaptureThreadOptions options);
  // Stops the thread; frames the consumer still holds become invalid.
  ~CaptureThread();
  CaptureThread(const CaptureThread&) = delete;
  CaptureThread& operator=(const CaptureThread&) = delete;

  // Spawns the thread, which applies the real-time settings and opens and
  // starts the source; returns the source's open/start error, if any.
  Result<void> start();
  // Asks the thread to stop and joins it (bounded by next_timeout_ms).
  void stop();

  // Consumer: waits up to timeout_ms (without spinning) for a frame and takes
  // the newest one. False on timeout or when the source has finished and the
  // ring is empty.
  bool acquire_latest(Frame* out, int timeout_ms);
  // Consumer: returns a frame obtained from acquire_latest().
  void release(const Frame& frame);

  // The source ended (replay without loop) or failed for good.
  bool finished() const { return finished_.load(std::memory_order_acquire); }
  bool failed() const { return failed_.load(std::memory_order_acquire); }
  CaptureStats stats() const;
  RealtimeStatus realtime() const { return realtime_; }  // valid after start()
  const std::string& description() const { return description_; }
  // The source's own camera model (a recording's recording.yaml, the
  // simulator's camera); false for cameras. Valid after start().
  bool camera_intrinsics(CameraIntrinsics* out) const { return source_->camera_intrinsics(out); }
  std::thread::native_handle_type native_handle() { return thread_.native_handle(); }

 private:
  void run(void* start_promise);
  void apply_realtime();
  void drain_returned();
  void return_to_capture(const Frame& frame);
  void publish_source_stats();

  std::unique_ptr<FrameSource> source_;
  const CaptureThreadOptions options_;
  std::thread thread_;
  std::string description_;
  RealtimeStatus realtime_;
  bool live_ = true;
  size_t budget_ = 1;     // frames allowed outside the source at once
  size_t in_flight_ = 0;  // capture thread only

  SpscRing<Frame, kRingCapacity> ready_;     // capture -> pipeline
  SpscRing<Frame, kRingCapacity> returned_;  // pipeline -> capture

  // Futex words: bumped after a push so that the other side can sleep on them.
  std::atomic<uint32_t> ready_seq_{0};
  std::atomic<uint32_t> returned_seq_{0};
  std::atomic<bool> stop_{false};
  std::atomic<bool> finished_{false};
  std::atomic<bool> failed_{false};

  std::atomic<uint64_t> frames_{0};
  std::atomic<uint64_t> drops_{0};
  std::atomic<uint64_t> skipped_{0};
  std::atomic<uint64_t> source_drops_{0};
  std::atomic<uint64_t> outages_{0};
  std::atomic<uint64_t> reconnects_{0};
  std::atomic<uint64_t> corrupt_{0};
};

}  // namespace ceilpose::capture
