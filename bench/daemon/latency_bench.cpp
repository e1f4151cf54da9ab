// End-to-end latency of ceilposed's frame path, frame ready (dequeued by the
// capture thread) to pose published on shared memory, using the daemon's own
// PipelineWorker: synthetic and replay sources at 30, 60 and 120 fps, 640x480,
// with the other core idle or busy (a spinning thread pinned to it); the
// synthetic camera in RGB24 or, as USB cameras deliver, YUYV (yuyv:1).
//
// Each case runs for --duration_s seconds (default 2) of wall time; the figures
// are counters: p50/p99/max in microseconds, frames, and the frames skipped or
// dropped to stay current ("backlog": the pipeline never works through a queue,
// so a pipeline slower than the camera shows up here, not as growing latency).
//   latency_bench                                   # all cases, 2 s each
//   latency_bench --duration_s=300 --benchmark_filter='synthetic/fps:60/load:0'
#include <benchmark/benchmark.h>
#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>

#include "capture/capture_thread.h"
#include "capture/frame_source.h"
#include "config/service_config.h"
#include "core/clock.h"
#include "daemon/pipeline_worker.h"
#include "daemon/shm_pose_sink.h"
#include "ipc/shm/shm_pose_writer.h"
#include "recording/recording_writer.h"
#include "sim/renderer.h"
#include "sim/scenarios.h"
#include "sim/trajectory_camera.h"

namespace ceilpose {
namespace {

double g_duration_s = 2.0;
// Frames not recorded: the first touch of the pipeline's buffers is not the steady state.
constexpr uint64_t kWarmupFrames = 5;
std::string g_replay_dir;

// Spins on one CPU until destroyed: "the other core loaded".
class BusyCore {
 public:
  explicit BusyCore(int cpu) {
    thread_ = std::thread([this, cpu] {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(cpu, &set);
      pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
      volatile uint64_t x = 0;
      while (!stop_.load(std::memory_order_relaxed)) x = x + 1;
    });
  }
  ~BusyCore() {
    stop_.store(true);
    thread_.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// A looping recording of the walking-speed trajectory, rendered once.
std::string replay_dir() {
  if (!g_replay_dir.empty()) return g_replay_dir;
  const std::string dir = "/tmp/ceilpose-latency-bench-" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  sim::SceneOptions options;
  auto scenario = sim::make_scenario("trajectory", options, 90, 7);
  if (!scenario) throw std::runtime_error(scenario.error().message);
  RecordingCamera camera;
  camera.intrinsics = options.intrinsics;
  camera.source = "latency_bench: sim trajectory";
  auto writer = RecordingWriter::create(dir, camera);
  if (!writer) throw std::runtime_error(writer.error().message);
  sim::Renderer renderer(options);
  Image frame;
  for (const auto& f : scenario->frames) {
    renderer.render(f.pose, f.mount, f.effects, f.seed, &frame);
    if (auto ok = writer->append(frame.view(), f.timestamp_ns, &f.pose); !ok)
      throw std::runtime_error(ok.error().message);
  }
  if (auto ok = writer->close(); !ok) throw std::runtime_error(ok.error().message);
  g_replay_dir = dir;
  return dir;
}

void BM_FrameToPose(benchmark::State& state, bool replay) {
  const double fps = static_cast<double>(state.range(0));
  const bool loaded = state.range(1) != 0;
  // The synthetic camera hands over YUYV, as a USB camera does (issue 29).
  const bool yuyv = !replay && state.range(2) != 0;
  // Tracked frames measured at the predicted markers' edges alone
  // (detector.track_edges).
  const bool edges = !replay && state.range(3) != 0;

  ServiceConfig config = default_config();
  config.capture.device.fps = fps;
  config.capture.thread.cpu = 0;  // capture on CPU 0; the load (if any) on CPU 1
  config.watchdog.status_interval_ms = 1000;
  config.pipeline.detector.track_edges = edges;
  std::string spec = "synthetic";
  capture::SourceOptions so = config.capture.device;
  sim::TrajectoryCameraOptions camera;
  camera.scene = sim::SceneOptions{config.pipeline.layout, config.pipeline.intrinsics, 1, nullptr};
  camera.mount = config.pipeline.mount;
  if (yuyv) camera.format = PixelFormat::kYuyv;
  if (replay) {
    spec = "replay:" + replay_dir();
    so.replay_speed = fps / 30.0;  // the recording is 30 fps
    so.replay_loop = true;
  }

  for (auto _ : state) {
    auto source = capture::make_frame_source(
        spec, so, replay ? nullptr : std::make_shared<sim::TrajectoryCamera>(camera));
    if (!source) {
      state.SkipWithError(source.error().message.c_str());
      return;
    }
    capture::CaptureThread capture(std::move(source).value(), config.capture.thread);
    if (auto r = capture.start(); !r) {
      state.SkipWithError(r.error().message.c_str());
      return;
    }
    ShmOptions sopts;
    sopts.name = "/ceilpose-latency-bench-" + std::to_string(getpid());
    auto shm = ShmPoseWriter::create(sopts);
    if (!shm) {
      state.SkipWithError(shm.error().message.c_str());
      return;
    }
    daemon::ShmPoseSink shm_sink(&*shm, config.watchdog.status_interval_ms);
    daemon::PublishingSink* sinks[] = {&shm_sink};
    daemon::ProgressCounter progress;
    daemon::WorkerOptions wopts;
    wopts.rt_priority = config.capture.pipeline_rt_priority;  // as ceilposed runs it
    wopts.cpu = config.capture.thread.cpu;
    wopts.latency_warmup_frames = kWarmupFrames;
    daemon::PipelineWorker worker(config, wopts, &capture, sinks, &progress);

    std::unique_ptr<BusyCore> busy;
    if (loaded) busy = std::make_unique<BusyCore>(1);
    const auto t0 = std::chrono::steady_clock::now();
    worker.start();
    const int64_t cpu_start_ns = worker.thread_cpu_ns(), wall_start_ns = monotonic_ns();
    // Backlog growth: skipped + dropped over the second half of the run
    // against the first half.
    std::this_thread::sleep_for(std::chrono::duration<double>(g_duration_s / 2));
    const capture::CaptureStats half = capture.stats();
    std::this_thread::sleep_for(std::chrono::duration<double>(g_duration_s / 2));
    // The pipeline thread's share of a core.
    state.counters["pipe_cpu_pct"] =
        100.0 * static_cast<double>(worker.thread_cpu_ns() - cpu_start_ns) /
        static_cast<double>(std::max<int64_t>(1, monotonic_ns() - wall_start_ns));
    worker.stop();
    capture.stop();
    busy.reset();
    const auto t1 = std::chrono::steady_clock::now();
    state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());

    const capture::CaptureStats end = capture.stats();
    const capture::LatencySummary lat = worker.latency().dequeue_to_published().summary();
    const capture::LatencySummary cap = worker.latency().capture_to_published().summary();
    state.counters["p50_us"] = static_cast<double>(lat.p50_us);
    state.counters["p99_us"] = static_cast<double>(lat.p99_us);
    state.counters["max_us"] = static_cast<double>(lat.max_us);
    state.counters["cap_p99_us"] = static_cast<double>(cap.p99_us);
    // The two parts of frame ready -> published: the pipeline thread's wake
    // (dequeued -> pipeline started) and its work (started -> published).
    state.counters["wake_p99_us"] =
        static_cast<double>(worker.latency().dequeue_to_pipeline().summary().p99_us);
    state.counters["work_p99_us"] =
        static_cast<double>(worker.latency().pipeline_to_published().summary().p99_us);
    state.counters["frames"] = static_cast<double>(worker.frames());
    // Whole sweeps set the tail: their share, and the two main reasons'.
    const SweepCounts& sweeps = worker.sweeps();
    const double swept =
        std::max<double>(1.0, static_cast<double>(sweeps.tracked() + sweeps.full()));
    auto share = [&](FullSweepReason r) {
      return static_cast<double>(sweeps.by_reason[static_cast<size_t>(r)]) / swept;
    };
    state.counters["whole_share"] = static_cast<double>(sweeps.full()) / swept;
    state.counters["uncertain_share"] = share(FullSweepReason::kUncertain);
    state.counters["scheduled_share"] = share(FullSweepReason::kScheduled);
    // Scheduled whole sweeps run after the pose (Localizer::check_scheduled).
    state.counters["checked_share"] = static_cast<double>(sweeps.checked) / swept;
    state.counters["check_failed"] = static_cast<double>(sweeps.check_failed);
    const double lost_first = static_cast<double>(half.skipped + half.drops);
    const double lost_all = static_cast<double>(end.skipped + end.drops);
    state.counters["skipped"] = lost_all;
    state.counters["skip_growth"] = (lost_all - lost_first) - lost_first;
    state.counters["fifo"] = (capture.realtime().fifo ? 1 : 0) + (worker.realtime() ? 1 : 0);
    (void)ShmPoseWriter::remove(sopts.name);
  }
}

void register_all() {
  for (bool replay : {false, true}) {
    const char* name = replay ? "replay" : "synthetic";
    auto* b = benchmark::RegisterBenchmark(
        name, [replay](benchmark::State& s) { BM_FrameToPose(s, replay); });
    if (replay)
      b->ArgsProduct({{30, 60, 120}, {0, 1}})->ArgNames({"fps", "load"});
    else
      b->ArgsProduct({{30, 60, 120}, {0, 1}, {0, 1}, {0, 1}})
          ->ArgNames({"fps", "load", "yuyv", "edges"});
    b->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);
  }
}

}  // namespace
}  // namespace ceilpose

int main(int argc, char** argv) {
  // Our own flag, removed before Google Benchmark sees the rest.
  int kept = 1;
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--duration_s=", 13) == 0) {
      ceilpose::g_duration_s = std::atof(argv[i] + 13);
    } else {
      argv[kept++] = argv[i];
    }
  }
  argc = kept;
  spdlog::set_level(spdlog::level::warn);
  benchmark::Initialize(&argc, argv);
  ceilpose::register_all();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (!ceilpose::g_replay_dir.empty()) std::filesystem::remove_all(ceilpose::g_replay_dir);
  return 0;
}
