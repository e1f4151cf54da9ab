#include "capture/latency_histogram.h"

#include <bit>
#include <cstdio>

namespace ceilpose::capture {

// Bucket b < 16 holds exactly the value b. Above, a value v with top bit e
// (2^e <= v < 2^(e+1), e >= 4) is split by its next kSubBits bits into 16
// equal buckets of width 2^(e-4): b = 16 + (e-4)*16 + ((v >> (e-4)) & 15).
int LatencyHistogram::bucket_of(uint64_t value_us) noexcept {
  if (value_us < static_cast<uint64_t>(kSubBuckets)) return static_cast<int>(value_us);
  const int e = 63 - std::countl_zero(value_us);
  if (e > kMaxExponent) return kBuckets - 1;
  const int shift = e - kSubBits;
  const int sub = static_cast<int>((value_us >> shift) & (kSubBuckets - 1));
  return kSubBuckets + shift * kSubBuckets + sub;
}

uint64_t LatencyHistogram::bucket_upper_us(int bucket) noexcept {
  if (bucket < kSubBuckets) return static_cast<uint64_t>(bucket);
  const int shift = (bucket - kSubBuckets) / kSubBuckets;
  const uint64_t sub = static_cast<uint64_t>((bucket - kSubBuckets) % kSubBuckets);
  const uint64_t lower = (static_cast<uint64_t>(kSubBuckets) + sub) << shift;
  return lower + (uint64_t{1} << shift) - 1;
}

// Single writer: a plain load+store per counter (no locked read-modify-write)
// is enough, and readers see each counter atomically.
void LatencyHistogram::record_us(uint64_t value_us) noexcept {
  auto& c = counts_[static_cast<size_t>(bucket_of(value_us))];
  c.store(c.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  sum_us_.store(sum_us_.load(std::memory_order_relaxed) + value_us, std::memory_order_relaxed);
  if (value_us > max_us_.load(std::memory_order_relaxed)) {
    max_us_.store(value_us, std::memory_order_relaxed);
  }
}

uint64_t LatencyHistogram::count() const noexcept {
  uint64_t n = 0;
  for (const auto& c : counts_) n += c.load(std::memory_order_relaxed);
  return n;
}

LatencySummary LatencyHistogram::summary() const noexcept {
  std::array<uint64_t, kBuckets> counts{};
  LatencySummary s;
  for (size_t i = 0; i < counts.size(); ++i) {
    counts[i] = counts_[i].load(std::memory_order_relaxed);
    s.count += counts[i];
  }
  s.max_us = max_us_.load(std::memory_order_relaxed);
  if (s.count == 0) return s;
  s.mean_us =
      static_cast<double>(sum_us_.load(std::memory_order_relaxed)) / static_cast<double>(s.count);
  // Rank r (1-based) = ceil(q * count): the smallest value with at least a
  // share q of the samples at or below it.
  auto percentile = [&](double q) {
    uint64_t rank = static_cast<uint64_t>(q * static_cast<double>(s.count));
    if (static_cast<double>(rank) < q * static_cast<double>(s.count)) ++rank;
    if (rank == 0) rank = 1;
    uint64_t seen = 0;
    for (int b = 0; b < kBuckets; ++b) {
      seen += counts[static_cast<size_t>(b)];
      if (seen >= rank) {
        const uint64_t upper = bucket_upper_us(b);
        return upper < s.max_us ? upper : s.max_us;
      }
    }
    return s.max_us;
  };
  s.p50_us = percentile(0.50);
  s.p90_us = percentile(0.90);
  s.p99_us = percentile(0.99);
  return s;
}

void FrameLatency::record(const FrameStamps& t) noexcept {
  if (t.capture_ns != 0 && t.dequeue_ns != 0) {
    capture_to_dequeue_.record_ns(t.dequeue_ns - t.capture_ns);
  }
  if (t.dequeue_ns != 0 && t.pipeline_start_ns != 0) {
    dequeue_to_pipeline_.record_ns(t.pipeline_start_ns - t.dequeue_ns);
  }
  if (t.pipeline_start_ns != 0 && t.published_ns != 0) {
    pipeline_to_published_.record_ns(t.published_ns - t.pipeline_start_ns);
  }
  if (t.dequeue_ns != 0 && t.published_ns != 0) {
    dequeue_to_published_.record_ns(t.published_ns - t.dequeue_ns);
  }
  if (t.capture_ns != 0 && t.published_ns != 0) {
    capture_to_published_.record_ns(t.published_ns - t.capture_ns);
  }
}

std::string format_summary(const char* name, const LatencySummary& s) {
  char line[200];
  std::snprintf(
      line, sizeof line, "%s n=%llu mean=%.0fus p50=%lluus p90=%lluus p99=%lluus max=%lluus", name,
      static_cast<unsigned long long>(s.count), s.mean_us,
      static_cast<unsigned long long>(s.p50_us), static_cast<unsigned long long>(s.p90_us),
      static_cast<unsigned long long>(s.p99_us), static_cast<unsigned long long>(s.max_us));
  return line;
}

std::string FrameLatency::report() const {
  std::string out;
  out += format_summary("capture->dequeue", capture_to_dequeue_.summary()) + "\n";
  out += format_summary("dequeue->pipeline", dequeue_to_pipeline_.summary()) + "\n";
  out += format_summary("pipeline->published", pipeline_to_published_.summary()) + "\n";
  out += format_summary("dequeue->published", dequeue_to_published_.summary()) + "\n";
  out += format_summary("capture->published", capture_to_published_.summary()) + "\n";
  return out;
}

}  // namespace ceilpose::capture
