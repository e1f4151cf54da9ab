#pragma once
// A FrameSource for tests of the capture thread: produces numbered frames from
// a few slots at a fixed period (or as fast as asked), optionally a finite
// number, and checks the slot protocol: a slot is never handed out twice and
// never released twice.
#include <algorithm>
#include <atomic>
#include <cstring>
#include <string>
#include <vector>

#include "capture/frame_source.h"
#include "capture/wait.h"
#include "core/clock.h"

namespace ceilpose::capture::testing {

class CountingSource final : public FrameSource {
 public:
  struct Options {
    int slots = 4;
    int64_t period_ns = 1'000'000;  // 0 = as fast as next() is called
    int64_t frame_limit = -1;       // -1 = endless
    bool live = true;
  };
  explicit CountingSource(Options o) : o_(o), slots_(static_cast<size_t>(o.slots)) {}

  std::string describe() const override { return "counting"; }
  SourceStats stats() const override { return stats_; }
  bool live() const override { return o_.live; }
  int buffers() const override { return o_.slots; }

  // Read after the capture thread is stopped.
  int64_t produced() const { return produced_; }
  int held() const {
    return static_cast<int>(
        std::count_if(slots_.begin(), slots_.end(), [](const Slot& s) { return s.busy; }));
  }
  int protocol_errors() const { return protocol_errors_; }
  int no_free_slot() const { return no_free_slot_; }

 protected:
  Result<void> do_open() override { return {}; }
  Result<void> do_start() override {
    start_ns_ = monotonic_ns();
    return {};
  }
  NextStatus do_next(Frame* out, int timeout_ms) override {
    if (o_.frame_limit >= 0 && produced_ >= o_.frame_limit) return NextStatus::kEndOfStream;
    const int64_t due_ns = start_ns_ + produced_ * o_.period_ns;
    const int64_t deadline_ns = monotonic_ns() + int64_t{timeout_ms} * 1'000'000;
    if (due_ns > deadline_ns) {
      sleep_until_ns(deadline_ns);
      return NextStatus::kTimeout;
    }
    sleep_until_ns(due_ns);
    auto it = std::find_if(slots_.begin(), slots_.end(), [](const Slot& s) { return !s.busy; });
    if (it == slots_.end()) {
      ++no_free_slot_;
      return NextStatus::kTimeout;
    }
    it->busy = true;
    it->value = static_cast<uint64_t>(produced_);
    Frame f;
    f.image =
        ImageView{reinterpret_cast<const uint8_t*>(&it->value), 1, 1, 8, PixelFormat::kGray8, 8};
    f.capture_ns = due_ns;
    f.dequeue_ns = monotonic_ns();
    f.sequence = static_cast<uint64_t>(produced_++);
    f.buffer_index = static_cast<int32_t>(it - slots_.begin());
    ++stats_.frames;
    *out = f;
    return NextStatus::kFrame;
  }
  void do_release(const Frame& f) override {
    Slot& s = slots_[static_cast<size_t>(f.buffer_index)];
    if (!s.busy || s.value != f.sequence) ++protocol_errors_;
    s.busy = false;
  }
  void do_stop() override {}

 private:
  struct Slot {
    bool busy = false;
    uint64_t value = 0;
  };
  Options o_;
  std::vector<Slot> slots_;
  int64_t start_ns_ = 0;
  int64_t produced_ = 0;
  int protocol_errors_ = 0;
  int no_free_slot_ = 0;
  SourceStats stats_;
};

}  // namespace ceilpose::capture::testing
