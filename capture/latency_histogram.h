#pragma once
// Fixed-bucket latency histograms for the frame path. One thread records (the
// one that owns the stage), any thread may take a snapshot. Recording is a few
// relaxed atomic loads/stores: no allocation, no lock, no syscall, so the
// capture and pipeline threads can record every frame.
#include <array>
#include <atomic>
#include <cstdint>
#include <string>

namespace ceilpose::capture {

struct LatencySummary {
  uint64_t count = 0;
  double mean_us = 0.0;
  uint64_t p50_us = 0;  // percentiles are bucket upper bounds (at most 1/16 high), capped at max
  uint64_t p90_us = 0;
  uint64_t p99_us = 0;
  uint64_t max_us = 0;
};

// Log-linear buckets in microseconds: exact below 16 µs, then 16 buckets per
// power of two (relative resolution 1/16 = 6 %), up to ~71 minutes; longer
// values land in the last bucket but still update max.
class LatencyHistogram {
 public:
  static constexpr int kSubBits = 4;
  static constexpr int kSubBuckets = 1 << kSubBits;
  static constexpr int kMaxExponent = 31;
  static constexpr int kBuckets = kSubBuckets + (kMaxExponent - kSubBits + 1) * kSubBuckets;

  // Single writer.
  void record_us(uint64_t value_us) noexcept;
  void record_ns(int64_t value_ns) noexcept {
    record_us(value_ns <= 0 ? 0 : static_cast<uint64_t>(value_ns) / 1000);
  }

  // Any thread. Percentiles are computed over the counts as read, which may
  // miss the sample being written at that instant.
  LatencySummary summary() const noexcept;
  uint64_t count() const noexcept;

  static int bucket_of(uint64_t value_us) noexcept;
  static uint64_t bucket_upper_us(int bucket) noexcept;

 private:
  std::array<std::atomic<uint64_t>, kBuckets> counts_{};
  std::atomic<uint64_t> sum_us_{0};
  std::atomic<uint64_t> max_us_{0};
};

// The four stamps a frame collects on its way to a published pose (all
// CLOCK_MONOTONIC ns): the capture thread sets the first two, the daemon's
// pipeline thread the last two. 0 means "not stamped".
struct FrameStamps {
  int64_t capture_ns = 0;         // driver/sensor time of exposure
  int64_t dequeue_ns = 0;         // capture thread got the buffer
  int64_t pipeline_start_ns = 0;  // pipeline thread started on it
  int64_t published_ns = 0;       // pose published (shared memory / DDS)
};

// Histograms per stage of the frame path, recorded by the pipeline thread (the
// only thread that has all four stamps).
class FrameLatency {
 public:
  void record(const FrameStamps& stamps) noexcept;

  const LatencyHistogram& capture_to_dequeue() const { return capture_to_dequeue_; }
  const LatencyHistogram& dequeue_to_pipeline() const { return dequeue_to_pipeline_; }
  const LatencyHistogram& pipeline_to_published() const { return pipeline_to_published_; }
  // Frame ready (dequeued) to pose published: the figure the service's
  // latency budget (under 1 ms) is about.
  const LatencyHistogram& dequeue_to_published() const { return dequeue_to_published_; }
  const LatencyHistogram& capture_to_published() const { return capture_to_published_; }

  // One line per stage, e.g. "dequeue->published n=900 p50=310us p90=402us p99=655us max=1210us".
  std::string report() const;

 private:
  LatencyHistogram capture_to_dequeue_;
  LatencyHistogram dequeue_to_pipeline_;
  LatencyHistogram pipeline_to_published_;
  LatencyHistogram dequeue_to_published_;
  LatencyHistogram capture_to_published_;
};

std::string format_summary(const char* name, const LatencySummary& s);

}  // namespace ceilpose::capture
