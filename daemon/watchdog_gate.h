#pragma once
// Decides whether the control thread may feed the systemd watchdog: only when
// the pipeline thread has finished a frame within max_stall_ns. A hung
// pipeline, a dead capture thread or a source that stopped delivering all stop
// frames, so they all starve the watchdog and let systemd restart us.
#include <atomic>
#include <cstdint>

namespace ceilpose::daemon {

// Advanced by the pipeline thread after every finished frame.
class ProgressCounter {
 public:
  void advance(int64_t now_ns) noexcept {
    last_ns_.store(now_ns, std::memory_order_relaxed);
    count_.fetch_add(1, std::memory_order_release);
  }
  uint64_t count() const noexcept { return count_.load(std::memory_order_acquire); }
  int64_t last_ns() const noexcept { return last_ns_.load(std::memory_order_relaxed); }

 private:
  std::atomic<uint64_t> count_{0};
  std::atomic<int64_t> last_ns_{0};
};

class WatchdogGate {
 public:
  explicit WatchdogGate(int64_t max_stall_ns) : max_stall_ns_(max_stall_ns) {}

  // True when the counter moved since the previous call, or it last moved
  // less than max_stall_ns before now_ns. Before the first frame: false.
  bool may_feed(const ProgressCounter& progress, int64_t now_ns) {
    const uint64_t count = progress.count();
    const bool moved = count != last_count_;
    last_count_ = count;
    if (count == 0) return false;
    return moved || now_ns - progress.last_ns() <= max_stall_ns_;
  }

 private:
  int64_t max_stall_ns_;
  uint64_t last_count_ = 0;
};

}  // namespace ceilpose::daemon
