// Benchmarks of the capture path. Run from a Release build:
//   ./build/release/bench/capture/capture_bench
// The hand-off benchmark reports the wake-up latency from "frame dequeued" on
// the capture thread to "acquire_latest returned" on the consumer, as
// histogram percentiles (counters p50_us, p99_us, max_us).
#include <benchmark/benchmark.h>

#include <memory>

#include "capture/capture_thread.h"
#include "capture/latency_histogram.h"
#include "capture/pixel_convert.h"
#include "capture/spsc_ring.h"
#include "capture/synthetic_source.h"
#include "core/clock.h"
#include "sim/trajectory_camera.h"
#include "tests/capture/counting_source.h"

namespace ceilpose::capture {
namespace {

void BM_RingPushPopFrame(benchmark::State& state) {
  SpscRing<Frame, 16> ring;
  Frame f;
  for (auto _ : state) {
    ring.try_push(f);
    benchmark::DoNotOptimize(ring.front());
    ring.pop();
  }
}
BENCHMARK(BM_RingPushPopFrame);

void BM_HistogramRecord(benchmark::State& state) {
  LatencyHistogram h;
  uint64_t v = 1;
  for (auto _ : state) {
    h.record_us(v);
    v = (v * 2654435761u) % 100000;
  }
  benchmark::DoNotOptimize(h.count());
}
BENCHMARK(BM_HistogramRecord);

void BM_HistogramSummary(benchmark::State& state) {
  LatencyHistogram h;
  for (uint64_t v = 0; v < 100000; ++v) h.record_us(v % 20000);
  for (auto _ : state) benchmark::DoNotOptimize(h.summary());
}
BENCHMARK(BM_HistogramSummary);

// Frames from a camera at the given rate through the capture thread to a
// consumer blocked in acquire_latest (futex wait): the per-frame cost the
// pipeline thread pays before it can start, and how late it wakes.
void BM_CaptureHandoffLatency(benchmark::State& state) {
  testing::CountingSource::Options so;
  so.period_ns = 1'000'000'000 / state.range(0);
  CaptureThreadOptions o;
  o.realtime_priority = 0;
  o.lock_memory = false;
  CaptureThread thread(std::make_unique<testing::CountingSource>(so), o);
  if (!thread.start()) {
    state.SkipWithError("capture thread failed to start");
    return;
  }
  LatencyHistogram wake;
  for (auto _ : state) {
    Frame f;
    if (!thread.acquire_latest(&f, 1000)) {
      state.SkipWithError("no frame within 1 s");
      break;
    }
    wake.record_ns(monotonic_ns() - f.dequeue_ns);
    thread.release(f);
  }
  thread.stop();
  const LatencySummary s = wake.summary();
  state.counters["p50_us"] = static_cast<double>(s.p50_us);
  state.counters["p99_us"] = static_cast<double>(s.p99_us);
  state.counters["max_us"] = static_cast<double>(s.max_us);
  state.counters["skipped"] = static_cast<double>(thread.stats().skipped);
}
BENCHMARK(BM_CaptureHandoffLatency)->Arg(120)->Arg(1000)->UseRealTime()->Iterations(600);

void BM_YuyvToRgb640x480(benchmark::State& state) {
  Image yuyv(640, 480, PixelFormat::kYuyv);
  for (size_t i = 0; i < yuyv.size_bytes(); ++i) yuyv.data()[i] = static_cast<uint8_t>(i * 7);
  Image rgb;
  for (auto _ : state) {
    auto r = to_rgb24(yuyv.view(), &rgb);
    benchmark::DoNotOptimize(r.ok());
  }
}
BENCHMARK(BM_YuyvToRgb640x480);

// One synthetic frame: trajectory pose plus a 640x480 render (the rate is
// set so high that next() never sleeps).
void BM_SyntheticFrame640x480(benchmark::State& state) {
  SourceOptions o;
  o.fps = 10000.0;
  SyntheticSource source(o,
                         std::make_shared<sim::TrajectoryCamera>(sim::TrajectoryCameraOptions{}));
  if (!source.open() || !source.start()) {
    state.SkipWithError("synthetic source failed to start");
    return;
  }
  for (auto _ : state) {
    Frame f;
    while (source.next(&f, 100) != NextStatus::kFrame) {
    }
    source.release(f);
  }
}
BENCHMARK(BM_SyntheticFrame640x480)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace ceilpose::capture

BENCHMARK_MAIN();
