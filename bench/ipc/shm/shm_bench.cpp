// Benchmarks of the shared-memory pose segment. Latencies are measured per
// sample with CLOCK_MONOTONIC, which both processes share, and reported as
// percentile counters in microseconds (p50_us, p90_us, p99_us, max_us).
//
//   BM_ReadLatest/<writer>   one read_latest() while a writer process is idle,
//                            publishes at 1 kHz, or publishes flat out
//   BM_Publish               one publish() with no waiting reader (wait-free path)
//   BM_PublishToVisible      writer process publishes every 500 us; a reader
//                            process spinning on read_latest() sees it after ...
//   BM_FutexWake             writer process publishes every 1 ms; a reader
//                            blocked in wait_next() returns after ...
//   BM_Predict               one ceilpose_client_predict() (the C API: read the
//                            latest pose, carry it 33 ms ahead) on an idle writer
#include <benchmark/benchmark.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "ceilpose/pose_client.h"
#include "core/clock.h"
#include "ipc/shm/shm_fleet_writer.h"
#include "ipc/shm/shm_pose_reader.h"
#include "ipc/shm/shm_pose_writer.h"

namespace ceilpose {
namespace {

std::string bench_shm_name(const char* what) {
  return "/ceilpose-bench-" + std::to_string(::getpid()) + "-" + what;
}

void report_percentiles(benchmark::State& state, std::vector<int64_t>& samples_ns) {
  if (samples_ns.empty()) {
    state.SkipWithError("no samples");
    return;
  }
  std::sort(samples_ns.begin(), samples_ns.end());
  auto at = [&](double q) {
    const size_t i = std::min(samples_ns.size() - 1, static_cast<size_t>(q * samples_ns.size()));
    return static_cast<double>(samples_ns[i]) / 1e3;
  };
  state.counters["p50_us"] = at(0.50);
  state.counters["p90_us"] = at(0.90);
  state.counters["p99_us"] = at(0.99);
  state.counters["max_us"] = static_cast<double>(samples_ns.back()) / 1e3;
  state.counters["samples"] = static_cast<double>(samples_ns.size());
}

// A child process that owns the writer and publishes every period_ns
// (0: as fast as it can) until killed. The parent opens the segment once the
// child has created it.
class WriterProcess {
 public:
  WriterProcess(const std::string& name, int64_t period_ns) : name_(name) {
    int ready[2];
    if (::pipe(ready) != 0) return;
    pid_ = ::fork();
    if (pid_ == 0) {
      ::close(ready[0]);
      ShmOptions options;
      options.name = name;
      auto writer = ShmPoseWriter::create(options);
      if (!writer) ::_exit(10);
      const char c = 1;
      if (::write(ready[1], &c, 1) != 1) ::_exit(11);
      PoseRecord p{};
      p.flags = kPoseValid;
      timespec next{};
      clock_gettime(CLOCK_MONOTONIC, &next);
      for (uint64_t k = 1;; ++k) {
        if (period_ns > 0) {
          next.tv_nsec += period_ns;
          while (next.tv_nsec >= 1'000'000'000) {
            next.tv_nsec -= 1'000'000'000;
            ++next.tv_sec;
          }
          clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
        }
        p.x_m = static_cast<double>(k);
        p.publish_mono_ns = 0;  // stamped by publish(), just before the stores
        writer->publish(p);
      }
    }
    ::close(ready[1]);
    char c = 0;
    ok_ = pid_ > 0 && ::read(ready[0], &c, 1) == 1;
    ::close(ready[0]);
  }
  ~WriterProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    (void)ShmPoseWriter::remove(name_);
  }
  bool ok() const { return ok_; }

 private:
  std::string name_;
  pid_t pid_ = -1;
  bool ok_ = false;
};

// state.range(0): writer period in us; 0 = no writer activity, -1 = flat out.
void BM_ReadLatest(benchmark::State& state) {
  const std::string name = bench_shm_name("read");
  const int64_t period_us = state.range(0);
  std::optional<WriterProcess> writer_process;
  std::optional<ShmPoseWriter> idle_writer;
  if (period_us == 0) {
    ShmOptions options;
    options.name = name;
    auto w = ShmPoseWriter::create(options);
    if (!w) return state.SkipWithError(w.error().message.c_str());
    idle_writer.emplace(std::move(w.value()));
    PoseRecord p{};
    p.flags = kPoseValid;
    idle_writer->publish(p);
  } else {
    writer_process.emplace(name, period_us < 0 ? 0 : period_us * 1000);
    if (!writer_process->ok()) return state.SkipWithError("writer process failed");
  }
  auto reader = ShmPoseReader::open(name);
  if (!reader) return state.SkipWithError(reader.error().message.c_str());
  std::vector<int64_t> samples;
  samples.reserve(static_cast<size_t>(state.max_iterations));
  PoseRecord p;
  uint64_t busy = 0;
  for (auto _ : state) {
    const int64_t t0 = monotonic_ns();
    const ReadResult r = reader->read_latest(&p);
    const int64_t t1 = monotonic_ns();
    benchmark::DoNotOptimize(p);
    if (r == ReadResult::kBusy) ++busy;
    samples.push_back(t1 - t0);
  }
  report_percentiles(state, samples);
  state.counters["busy"] = static_cast<double>(busy);
  if (period_us == 0) (void)ShmPoseWriter::remove(name);
}
// Samples include two clock reads (~20-40 ns): the figures are upper bounds.
BENCHMARK(BM_ReadLatest)->Arg(0)->Arg(1000)->Arg(-1)->Iterations(2'000'000)->UseRealTime();

void BM_Predict(benchmark::State& state) {
  const std::string name = bench_shm_name("predict");
  ShmOptions options;
  options.name = name;
  auto writer = ShmPoseWriter::create(options);
  if (!writer) return state.SkipWithError(writer.error().message.c_str());
  PoseRecord p{};
  p.flags = kPoseValid | kPoseFiltered;
  p.capture_mono_ns = monotonic_ns();
  MotionEstimate m;
  m.valid = true;
  m.time_ns = p.capture_mono_ns;
  m.state.x = {1.0, 2.0, 0.5, 1.2, 0.3, 0.8, 0.5, -0.4, 0.1};
  for (int i = 0; i < kMotionStates; ++i) m.state.p[i * kMotionStates + i] = 1e-4;
  m.jerk = {100.0, 100.0, 90000.0};
  m.horizon_ms = 200.0;
  set_pose_motion(&p, m);
  writer->publish(p);
  ceilpose_client* client = nullptr;
  if (ceilpose_client_open(name.c_str(), &client) != CEILPOSE_OK)
    return state.SkipWithError(ceilpose_last_error_message());
  ceilpose_pose out;
  const int64_t t_ns = p.capture_mono_ns + 33'000'000;
  for (auto _ : state) {
    const int rc = ceilpose_client_predict(client, t_ns, &out);
    benchmark::DoNotOptimize(rc);
    benchmark::DoNotOptimize(out);
  }
  ceilpose_client_close(client);
  (void)ShmPoseWriter::remove(name);
}
BENCHMARK(BM_Predict);

// A controller's whole fleet each cycle: N robots read from the fleet
// segment, each carried to "now" with its covariance (issue 26's goal at
// 50 robots: <= 10 us, <= 200 ns a robot). Slots are filled as the keeper
// fills them, every robot moving with a full motion state.
void BM_FleetSnapshot(benchmark::State& state) {
  const auto robots = static_cast<uint32_t>(state.range(0));
  const bool predicted = state.range(1) != 0;
  const std::string shm = bench_shm_name("fleet");
  ShmFleetOptions options;
  options.name = fleet_segment_name(shm);
  options.capacity = 256;
  auto writer = ShmFleetWriter::create(options);
  if (!writer) return state.SkipWithError(writer.error().message.c_str());
  const int64_t now_ns = monotonic_ns();
  for (uint32_t i = 0; i < robots; ++i) {
    shm::FleetRecord r{};
    std::snprintf(r.robot, sizeof r.robot, "robot%u", i);
    r.pose.flags = kPoseValid | kPoseFiltered;
    r.pose.capture_mono_ns = now_ns - 20'000'000;
    MotionEstimate m;
    m.valid = true;
    m.time_ns = r.pose.capture_mono_ns;
    m.state.x = {0.1 * i, 2.0, 0.5, 1.2, 0.3, 0.8, 0.5, -0.4, 0.1};
    for (int k = 0; k < kMotionStates; ++k) m.state.p[k * kMotionStates + k] = 1e-4;
    m.jerk = {100.0, 100.0, 90000.0};
    m.horizon_ms = 200.0;
    set_pose_motion(&r.pose, m);
    r.received_mono_ns = now_ns;
    writer->store(i, r);
  }
  ceilpose_fleet* fleet = nullptr;
  if (ceilpose_client_fleet_open(shm.c_str(), &fleet) != CEILPOSE_OK)
    return state.SkipWithError(ceilpose_last_error_message());
  std::vector<ceilpose_fleet_robot> out(256);
  uint32_t count = 0;
  for (auto _ : state) {
    const int rc =
        ceilpose_client_fleet_read(fleet, predicted ? now_ns : 0, out.data(), 256, &count);
    benchmark::DoNotOptimize(rc);
    benchmark::DoNotOptimize(out.data());
  }
  if (count != robots) state.SkipWithError("the snapshot missed robots");
  state.counters["ns_per_robot"] = benchmark::Counter(
      static_cast<double>(robots),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  ceilpose_client_fleet_close(fleet);
  (void)ShmFleetWriter::remove(options.name);
}
// Args: robots, predicted to now (1) or as received (0).
BENCHMARK(BM_FleetSnapshot)->ArgsProduct({{10, 50, 256}, {1, 0}});

void BM_Publish(benchmark::State& state) {
  const std::string name = bench_shm_name("publish");
  ShmOptions options;
  options.name = name;
  auto writer = ShmPoseWriter::create(options);
  if (!writer) return state.SkipWithError(writer.error().message.c_str());
  auto reader = ShmPoseReader::open(name);  // attached but not waiting
  PoseRecord p{};
  p.flags = kPoseValid;
  for (auto _ : state) {
    p.x_m += 1.0;
    writer->publish(p);
  }
  state.counters["wake_syscalls"] = static_cast<double>(writer->wake_syscalls());
  (void)ShmPoseWriter::remove(name);
}
BENCHMARK(BM_Publish);

void BM_PublishToVisible(benchmark::State& state) {
  const std::string name = bench_shm_name("visible");
  WriterProcess writer(name, 500'000);
  if (!writer.ok()) return state.SkipWithError("writer process failed");
  auto reader = ShmPoseReader::open(name);
  if (!reader) return state.SkipWithError(reader.error().message.c_str());
  std::vector<int64_t> samples;
  uint64_t last = reader->latest_seq();
  PoseRecord p;
  for (auto _ : state) {
    for (;;) {
      if (reader->latest_seq() != last && reader->read_latest(&p) == ReadResult::kOk) break;
    }
    samples.push_back(monotonic_ns() - p.publish_mono_ns);
    last = p.seq;
  }
  report_percentiles(state, samples);
}
BENCHMARK(BM_PublishToVisible)->Iterations(4000)->UseRealTime();

void BM_FutexWake(benchmark::State& state) {
  const std::string name = bench_shm_name("wake");
  WriterProcess writer(name, 1'000'000);
  if (!writer.ok()) return state.SkipWithError("writer process failed");
  auto reader = ShmPoseReader::open(name);
  if (!reader) return state.SkipWithError(reader.error().message.c_str());
  std::vector<int64_t> samples;
  uint64_t last = reader->latest_seq();
  PoseRecord p;
  uint64_t missed = 0;
  for (auto _ : state) {
    const WaitResult r = reader->wait_next(last, 1000, &p);
    const int64_t woke_ns = monotonic_ns();
    if (r != WaitResult::kPose) {
      state.SkipWithError(to_string(r));
      break;
    }
    // If the writer published twice before we ran, the sample is not a wake-up.
    if (p.seq == last + 1) {
      samples.push_back(woke_ns - p.publish_mono_ns);
    } else {
      ++missed;
    }
    last = p.seq;
  }
  report_percentiles(state, samples);
  state.counters["overrun"] = static_cast<double>(missed);
}
BENCHMARK(BM_FutexWake)->Iterations(3000)->UseRealTime();

}  // namespace
}  // namespace ceilpose

BENCHMARK_MAIN();
