#include "capture/capture_thread.h"

#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <future>

#include "capture/wait.h"
#include "core/clock.h"
#include "core/futex.h"
#include "core/thread_affinity.h"

namespace ceilpose::capture {
namespace {

// The privilege warnings are process-wide facts: say them once per process,
// not once per capture thread (tests and the daemon may start several).
std::atomic<bool> g_warned_fifo{false};
std::atomic<bool> g_warned_affinity{false};
std::atomic<bool> g_warned_mlock{false};

bool first_time(std::atomic<bool>& flag) { return !flag.exchange(true); }

}  // namespace

CaptureThread::CaptureThread(std::unique_ptr<FrameSource> source, CaptureThreadOptions options)
    : source_(std::move(source)), options_(options), description_(source_->describe()) {}

CaptureThread::~CaptureThread() { stop(); }

Result<void> CaptureThread::start() {
  if (thread_.joinable()) return make_error(description_ + ": capture thread already started");
  std::promise<Result<void>> started;
  auto result = started.get_future();
  stop_.store(false);
  finished_.store(false);
  failed_.store(false);
  thread_ = std::thread([this, &started] { run(&started); });
  Result<void> r = result.get();
  if (!r) {
    thread_.join();
    return r;
  }
  description_ = source_->describe();
  return r;
}

void CaptureThread::stop() {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

void CaptureThread::apply_realtime() {
  if (options_.realtime_priority > 0) {
    sched_param sp{};
    sp.sched_priority = options_.realtime_priority;
    const int r = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
    if (r == 0) {
      realtime_.fifo = true;
      realtime_.priority = options_.realtime_priority;
    } else if (first_time(g_warned_fifo)) {
      spdlog::warn(
          "capture thread: cannot run SCHED_FIFO at priority {}: {} (needs CAP_SYS_NICE or "
          "RLIMIT_RTPRIO, e.g. systemd LimitRTPRIO=); continuing at normal priority, so frame "
          "latency is not bounded under load",
          options_.realtime_priority, std::strerror(r));
    }
  }
  if (options_.cpu >= 0) {
    const int r = pin_thread_to_cpu(pthread_self(), options_.cpu);
    if (r == 0) {
      realtime_.pinned = true;
    } else if (first_time(g_warned_affinity)) {
      spdlog::warn("capture thread: cannot pin to CPU {}: {}; running on any CPU", options_.cpu,
                   std::strerror(r));
    }
  }
  if (options_.lock_memory) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    // Sanitizers reserve terabytes of shadow memory; locking it would exhaust RAM.
    if (first_time(g_warned_mlock)) {
      spdlog::info("capture thread: sanitizer build, memory not locked");
    }
#else
    if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      realtime_.memory_locked = true;
    } else if (first_time(g_warned_mlock)) {
      spdlog::warn(
          "capture thread: cannot lock memory (mlockall): {} (needs CAP_IPC_LOCK or "
          "RLIMIT_MEMLOCK, e.g. systemd LimitMEMLOCK=infinity); page faults may delay "
          "frames",
          std::strerror(errno));
    }
#endif
  }
}

void CaptureThread::run(void* start_promise) {
  auto* started = static_cast<std::promise<Result<void>>*>(start_promise);
  apply_realtime();
  Result<void> r = source_->open();
  if (r) r = source_->start();
  if (!r) {
    finished_.store(true, std::memory_order_release);
    failed_.store(true, std::memory_order_release);
    started->set_value(r);
    return;
  }
  live_ = source_->live();
  budget_ =
      static_cast<size_t>(std::clamp(source_->buffers() - 1, 1, static_cast<int>(kRingCapacity)));
  in_flight_ = 0;
  started->set_value(Result<void>{});  // `started` dies with start() after this line

  while (!stop_.load(std::memory_order_acquire)) {
    drain_returned();
    if (!live_ && in_flight_ >= budget_) {
      // Lossless mode: the source can wait for the pipeline.
      const uint32_t seen = returned_seq_.load(std::memory_order_acquire);
      drain_returned();
      if (in_flight_ >= budget_) {
        futex_wait(&returned_seq_, seen, static_cast<int64_t>(options_.next_timeout_ms) * 1'000'000,
                   FutexScope::kProcess);
      }
      continue;
    }
    Frame frame;
    const NextStatus s = source_->next(&frame, options_.next_timeout_ms);
    if (s == NextStatus::kFrame) {
      if (in_flight_ >= budget_ || !ready_.try_push(frame)) {
        source_->release(frame);
        drops_.fetch_add(1, std::memory_order_relaxed);
      } else {
        ++in_flight_;
        frames_.fetch_add(1, std::memory_order_relaxed);
        ready_seq_.fetch_add(1, std::memory_order_release);
        futex_wake_all(&ready_seq_, FutexScope::kProcess);
      }
    } else if (s == NextStatus::kEndOfStream || s == NextStatus::kError) {
      if (s == NextStatus::kError) failed_.store(true, std::memory_order_release);
      break;
    }
    publish_source_stats();
  }
  publish_source_stats();
  finished_.store(true, std::memory_order_release);
  ready_seq_.fetch_add(1, std::memory_order_release);
  futex_wake_all(&ready_seq_, FutexScope::kProcess);
  // The pipeline may still hold frames or have some in the ring: they stay
  // valid (the source keeps its buffers) until this object is destroyed.
  drain_returned();
  source_->stop();
}

void CaptureThread::drain_returned() {
  while (Frame* f = returned_.front()) {
    source_->release(*f);
    returned_.pop();
    if (in_flight_ > 0) --in_flight_;
  }
}

void CaptureThread::publish_source_stats() {
  const SourceStats s = source_->stats();
  source_drops_.store(s.drops, std::memory_order_relaxed);
  outages_.store(s.outages, std::memory_order_relaxed);
  reconnects_.store(s.reconnects, std::memory_order_relaxed);
  corrupt_.store(s.corrupt, std::memory_order_relaxed);
}

bool CaptureThread::acquire_latest(Frame* out, int timeout_ms) {
  const int64_t deadline_ns = monotonic_ns() + static_cast<int64_t>(timeout_ms) * 1'000'000;
  for (;;) {
    // Read the counter before looking at the ring: a push after the look
    // bumps it, so the futex wait below cannot miss it.
    const uint32_t seen = ready_seq_.load(std::memory_order_acquire);
    bool got = false;
    while (Frame* f = ready_.front()) {
      if (got) {
        return_to_capture(*out);
        skipped_.fetch_add(1, std::memory_order_relaxed);
      }
      *out = *f;
      ready_.pop();
      got = true;
      if (!live_) break;  // lossless: oldest first, nothing skipped
    }
    if (got) return true;
    if (finished_.load(std::memory_order_acquire) && ready_.front() == nullptr) return false;
    const int64_t remaining_ns = deadline_ns - monotonic_ns();
    if (remaining_ns <= 0) return false;
    futex_wait(&ready_seq_, seen, remaining_ns, FutexScope::kProcess);
  }
}

void CaptureThread::release(const Frame& frame) { return_to_capture(frame); }

void CaptureThread::return_to_capture(const Frame& frame) {
  // Cannot fail: at most budget_ <= kRingCapacity frames are ever outside the
  // source, so the return ring always has room for each of them.
  [[maybe_unused]] const bool ok = returned_.try_push(frame);
  returned_seq_.fetch_add(1, std::memory_order_release);
  if (!live_) futex_wake_all(&returned_seq_, FutexScope::kProcess);
}

CaptureStats CaptureThread::stats() const {
  CaptureStats s;
  s.frames = frames_.load(std::memory_order_relaxed);
  s.drops = drops_.load(std::memory_order_relaxed);
  s.skipped = skipped_.load(std::memory_order_relaxed);
  s.source_drops = source_drops_.load(std::memory_order_relaxed);
  s.outages = outages_.load(std::memory_order_relaxed);
  s.reconnects = reconnects_.load(std::memory_order_relaxed);
  s.corrupt = corrupt_.load(std::memory_order_relaxed);
  return s;
}

}  // namespace ceilpose::capture
