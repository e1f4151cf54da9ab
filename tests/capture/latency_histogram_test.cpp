// LatencyHistogram: bucket geometry, percentiles, stage recording.
#include "capture/latency_histogram.h"

#include <gtest/gtest.h>

#include <thread>

namespace ceilpose::capture {
namespace {

TEST(LatencyHistogram, EveryValueLiesInsideItsBucketWithinOneSixteenth) {
  for (uint64_t v : {0ull, 1ull, 15ull, 16ull, 17ull, 31ull, 32ull, 100ull, 999ull, 1000ull,
                     123456ull, 4'000'000'000ull}) {
    const int b = LatencyHistogram::bucket_of(v);
    const uint64_t upper = LatencyHistogram::bucket_upper_us(b);
    EXPECT_GE(upper, v) << v;
    EXPECT_LE(static_cast<double>(upper - v), static_cast<double>(v) / 16.0 + 1.0) << v;
    if (b > 0) {
      EXPECT_LT(LatencyHistogram::bucket_upper_us(b - 1), v) << v;
    }
  }
}

TEST(LatencyHistogram, BucketsAreContiguousAndIncreasing) {
  for (int b = 1; b < LatencyHistogram::kBuckets; ++b) {
    EXPECT_EQ(LatencyHistogram::bucket_of(LatencyHistogram::bucket_upper_us(b - 1) + 1), b) << b;
  }
}

TEST(LatencyHistogram, PercentilesOfAUniformSpreadAreWithinBucketResolution) {
  LatencyHistogram h;
  for (uint64_t v = 1; v <= 10000; ++v) h.record_us(v);
  const LatencySummary s = h.summary();
  EXPECT_EQ(s.count, 10000u);
  EXPECT_EQ(s.max_us, 10000u);
  EXPECT_NEAR(s.mean_us, 5000.5, 1e-9);
  EXPECT_GE(s.p50_us, 5000u);
  EXPECT_LE(s.p50_us, 5000u + 5000u / 16);
  EXPECT_GE(s.p90_us, 9000u);
  EXPECT_LE(s.p90_us, 9000u + 9000u / 16);
  EXPECT_GE(s.p99_us, 9900u);
  EXPECT_LE(s.p99_us, 10000u);  // capped at the maximum
}

TEST(LatencyHistogram, AnEmptyHistogramSummarisesToZeros) {
  LatencyHistogram h;
  const LatencySummary s = h.summary();
  EXPECT_EQ(s.count, 0u);
  EXPECT_EQ(s.p99_us, 0u);
  EXPECT_EQ(s.max_us, 0u);
}

TEST(LatencyHistogram, NegativeDurationsCountAsZero) {
  LatencyHistogram h;
  h.record_ns(-5000);
  EXPECT_EQ(h.summary().count, 1u);
  EXPECT_EQ(h.summary().max_us, 0u);
}

TEST(FrameLatency, RecordsEachStageFromItsStamps) {
  FrameLatency latency;
  FrameStamps t;
  t.capture_ns = 1'000'000;
  t.dequeue_ns = 3'000'000;         // +2 ms
  t.pipeline_start_ns = 3'100'000;  // +100 µs
  t.published_ns = 4'100'000;       // +1 ms
  latency.record(t);
  EXPECT_EQ(latency.capture_to_dequeue().summary().max_us, 2000u);
  EXPECT_EQ(latency.dequeue_to_pipeline().summary().max_us, 100u);
  EXPECT_EQ(latency.pipeline_to_published().summary().max_us, 1000u);
  EXPECT_EQ(latency.dequeue_to_published().summary().max_us, 1100u);
  EXPECT_EQ(latency.capture_to_published().summary().max_us, 3100u);
  EXPECT_NE(latency.report().find("dequeue->published n=1"), std::string::npos) << latency.report();
}

TEST(FrameLatency, UnsetStampsLeaveTheirStagesEmpty) {
  FrameLatency latency;
  FrameStamps t;
  t.capture_ns = 1'000'000;
  t.dequeue_ns = 2'000'000;
  latency.record(t);
  EXPECT_EQ(latency.capture_to_dequeue().count(), 1u);
  EXPECT_EQ(latency.pipeline_to_published().count(), 0u);
  EXPECT_EQ(latency.capture_to_published().count(), 0u);
}

TEST(LatencyHistogram, ASnapshotFromAnotherThreadNeverSeesMoreThanWasRecorded) {
  LatencyHistogram h;
  constexpr uint64_t kSamples = 200'000;
  std::thread writer([&] {
    for (uint64_t i = 0; i < kSamples; ++i) h.record_us(i % 5000);
  });
  uint64_t last = 0;
  while (last < kSamples) {
    const uint64_t n = h.summary().count;
    ASSERT_GE(n, last) << "counts only grow";
    ASSERT_LE(n, kSamples);
    last = n;
    if (n == kSamples) break;
    std::this_thread::yield();
  }
  writer.join();
  EXPECT_EQ(h.summary().count, kSamples);
}

}  // namespace
}  // namespace ceilpose::capture
