// The pipeline thread against a real capture thread (synthetic source) and a
// real shared-memory writer, while the control thread reads snapshots and
// reloads the configuration: the concurrency the daemon lives with. Runs
// under ThreadSanitizer (label tsan).
#include "daemon/pipeline_worker.h"

#include <gtest/gtest.h>
#include <sched.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "capture/capture_thread.h"
#include "capture/frame_source.h"
#include "daemon/pose_record_of.h"
#include "daemon/shm_pose_sink.h"
#include "ipc/shm/shm_pose_reader.h"
#include "ipc/shm/shm_pose_writer.h"
#include "sim/trajectory_camera.h"
#include "tests/support/alloc_count.h"

namespace ceilpose::daemon {
namespace {

struct Rig {
  Rig() {
    capture::SourceOptions so;
    so.fps = 30.0;
    sim::TrajectoryCameraOptions camera;
    camera.scene =
        sim::SceneOptions{config.pipeline.layout, config.pipeline.intrinsics, 1, nullptr};
    camera.mount = config.pipeline.mount;
    auto source = capture::make_frame_source("synthetic", so,
                                             std::make_shared<sim::TrajectoryCamera>(camera));
    if (!source) throw std::runtime_error(source.error().message);
    capture::CaptureThreadOptions copts;
    copts.realtime_priority = 0;  // tests run unprivileged too
    copts.lock_memory = false;
    capture = std::make_unique<capture::CaptureThread>(std::move(source).value(), copts);
    if (auto r = capture->start(); !r) throw std::runtime_error(r.error().message);
    ShmOptions sopts;
    sopts.name = shm_name;
    auto w = ShmPoseWriter::create(sopts);
    if (!w) throw std::runtime_error(w.error().message);
    shm.emplace(std::move(w).value());
    shm_sink.emplace(&*shm, status_interval_ms);
    sinks.push_back(&*shm_sink);
  }
  ~Rig() {
    capture->stop();
    shm.reset();
    (void)ShmPoseWriter::remove(shm_name);
  }

  ServiceConfig config = default_config();
  std::string shm_name = "/ceilpose-worker-test-" + std::to_string(getpid());
  std::unique_ptr<capture::CaptureThread> capture;
  std::optional<ShmPoseWriter> shm;
  int status_interval_ms = 50;
  std::optional<ShmPoseSink> shm_sink;
  std::vector<PublishingSink*> sinks;
  ProgressCounter progress;
};

// Waits (bounded) until the worker has processed `n` frames.
bool wait_frames(const PipelineWorker& worker, uint64_t n) {
  for (int i = 0; i < 3000 && worker.frames() < n; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  return worker.frames() >= n;
}

TEST(PipelineWorker, PublishesEveryProcessedFrameAndCountsProgress) {
  Rig rig;
  PipelineWorker worker(rig.config, WorkerOptions{}, rig.capture.get(), rig.sinks, &rig.progress);
  worker.start();
  ASSERT_TRUE(wait_frames(worker, 10));
  worker.stop();
  EXPECT_EQ(rig.shm->last_seq(), worker.frames());
  EXPECT_EQ(rig.progress.count(), worker.frames());
  EXPECT_EQ(worker.latency().dequeue_to_published().count(), worker.frames());
  EXPECT_FALSE(worker.finished()) << "stopped on request, not by the source";
}

// latency_bench's pipe_cpu_pct: the thread's own CPU clock, read from
// another thread while it runs.
TEST(PipelineWorker, ReportsItsThreadsCpuTimeWhileItRuns) {
  Rig rig;
  PipelineWorker worker(rig.config, WorkerOptions{}, rig.capture.get(), rig.sinks, &rig.progress);
  EXPECT_EQ(worker.thread_cpu_ns(), 0) << "no thread yet";
  worker.start();
  ASSERT_TRUE(wait_frames(worker, 3));
  const int64_t first_ns = worker.thread_cpu_ns();
  EXPECT_GT(first_ns, 0) << "three frames localized cost no CPU";
  ASSERT_TRUE(wait_frames(worker, worker.frames() + 3));
  EXPECT_GE(worker.thread_cpu_ns(), first_ns);
  worker.stop();
  EXPECT_EQ(worker.thread_cpu_ns(), 0) << "a joined thread's clock read";
}

// A worker pinned to `cpu` (WorkerOptions::cpu), started.
std::unique_ptr<PipelineWorker> start_on_cpu(Rig& rig, int cpu) {
  WorkerOptions options;
  options.cpu = cpu;
  auto worker = std::make_unique<PipelineWorker>(rig.config, options, rig.capture.get(), rig.sinks,
                                                 &rig.progress);
  worker->start();
  return worker;
}

// ceilposed pins the pipeline thread to capture.cpu: every frame is
// localized and published on that CPU.
TEST(PipelineWorker, PinnedToACpuLocalizesEveryFrameThere) {
  struct CpuSink final : PublishingSink {
    void consume(const Localization&) override {
      ++frames;
      if (sched_getcpu() != 0) ++elsewhere;
    }
    void publish_status(const ServiceStatus&) override {}
    int64_t status_period_ns() const override { return 1'000'000'000; }
    uint64_t frames = 0, elsewhere = 0;
  };
  Rig rig;
  CpuSink cpu_sink;
  rig.sinks.push_back(&cpu_sink);
  const auto worker = start_on_cpu(rig, 0);
  EXPECT_TRUE(worker->pinned());
  ASSERT_TRUE(wait_frames(*worker, 5));
  worker->stop();
  EXPECT_EQ(cpu_sink.frames, worker->frames());
  EXPECT_EQ(cpu_sink.elsewhere, 0u) << "frames localized off CPU 0";
}

// A CPU the process may not use (capture.cpu beyond the machine's) leaves
// the thread unpinned and says so; the frames still flow.
TEST(PipelineWorker, ACpuThatCannotBeHadLeavesItUnpinnedAndRunning) {
  Rig rig;
  const auto worker = start_on_cpu(rig, 1023);
  EXPECT_FALSE(worker->pinned());
  EXPECT_EQ(worker->pin_error(), EINVAL) << "the reason ceilposed logs";
  ASSERT_TRUE(wait_frames(*worker, 3));
  worker->stop();
}

TEST(PipelineWorker, SnapshotsAndReloadsFromAnotherThreadKeepTheSequenceRising) {
  Rig rig;
  PipelineWorker worker(rig.config, WorkerOptions{}, rig.capture.get(), rig.sinks, &rig.progress);
  worker.start();
  ASSERT_TRUE(wait_frames(worker, 2));
  uint64_t last_seq = 0;
  ServiceConfig changed = rig.config;
  for (int i = 0; i < 30; ++i) {
    changed.pipeline.detector.min_rect_area_px = (i % 2 == 0) ? 1 << 23 : 150;
    worker.reload(changed, i % 3 == 0);
    const PoseSnapshot s = worker.latest();
    EXPECT_GE(s.frame, last_seq);
    last_seq = s.frame;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const uint64_t before = worker.frames();
  ASSERT_TRUE(wait_frames(worker, before + 5)) << "stream stopped after reloads";
  worker.stop();
  EXPECT_EQ(rig.shm->last_seq(), worker.frames());
}

// Waits (bounded) until a snapshot satisfies `ok`.
template <typename Pred>
bool wait_snapshot(const PipelineWorker& worker, Pred ok) {
  for (int i = 0; i < 3000; ++i) {
    if (ok(worker.latest())) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

TEST(PipelineWorker, AReloadTakesEffectOnTheFollowingFrames) {
  // Handshakes on what the frames show, not on time: a rectangle size no
  // marker has makes every frame refused, and putting it back restores poses.
  Rig rig;
  PipelineWorker worker(rig.config, WorkerOptions{}, rig.capture.get(), rig.sinks, &rig.progress);
  worker.start();
  ASSERT_TRUE(wait_snapshot(worker, [](const PoseSnapshot& s) { return s.valid; }));
  ServiceConfig blind = rig.config;
  blind.pipeline.detector.min_rect_area_px = 1 << 23;
  blind.pipeline.filter.enabled = false;  // no coasting through the refused frames
  worker.reload(blind, true);
  ASSERT_TRUE(wait_snapshot(worker, [](const PoseSnapshot& s) {
    return !s.valid && s.refusal == Refusal::kNoMarkers;
  })) << "the reload never reached the pipeline thread";
  const uint64_t refused_before = worker.refusals()[Refusal::kNoMarkers];
  worker.reload(rig.config, true);
  ASSERT_TRUE(wait_snapshot(worker, [](const PoseSnapshot& s) { return s.valid; }))
      << "the second reload never reached the pipeline thread";
  worker.stop();
  EXPECT_GT(refused_before, 0u);
}

TEST(PipelineWorker, StatusRecordReachesReaders) {
  Rig rig;
  PipelineWorker worker(rig.config, WorkerOptions{}, rig.capture.get(), rig.sinks, &rig.progress);
  worker.start();
  ASSERT_TRUE(wait_frames(worker, 10));
  auto reader = ShmPoseReader::open(rig.shm_name);
  ASSERT_TRUE(reader) << reader.error().message;
  StatusRecord status{};
  bool seen = false;
  for (int i = 0; i < 300 && !seen; ++i) {
    // The first status interval may hold no processed frame (fps 0) on a slow
    // (sanitized, loaded) machine; a later one must show the stream's rate.
    seen = reader->read_status(&status) == ReadResult::kOk && status.frames > 0 && status.fps > 0.0;
    if (!seen) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  worker.stop();
  ASSERT_TRUE(seen) << "no status with frames and a positive fps within 3 s; last fps "
                    << status.fps << ", frames " << status.frames;
  EXPECT_NE(std::string(status.source).find("synthetic"), std::string::npos) << status.source;
  // Every localized frame is in the refusal histogram, under its reason.
  EXPECT_EQ(status.refusal_count, static_cast<uint32_t>(kRefusalCount));
  uint64_t counted = 0;
  for (uint32_t i = 0; i < status.refusal_count; ++i) counted += status.refusals[i];
  EXPECT_GT(counted, 0u);
  EXPECT_LE(counted, worker.frames());
  EXPECT_GT(status.refusals[0], 0u) << "the synthetic ceiling gives poses";
}

TEST(PipelineWorker, EveryFrameReachesEverySinkWithItsRefusal) {
  // A sink that records what it was given, checked after stop() (the worker
  // thread is then joined: no race on the fields).
  struct CountingSink final : PublishingSink {
    void consume(const Localization& loc) override {
      ++frames;
      if (!loc.published.valid && loc.published.refusal == Refusal::kNone) ++invalid_without_reason;
      if (loc.published.valid) ++valid;
    }
    void publish_status(const ServiceStatus& s) override {
      ++statuses;
      last_refusals = s.refusals;
    }
    int64_t status_period_ns() const override { return 20'000'000; }
    uint64_t frames = 0, valid = 0, invalid_without_reason = 0, statuses = 0;
    RefusalHistogram::Counts last_refusals{};
  };
  Rig rig;
  CountingSink counting;
  rig.sinks.push_back(&counting);
  PipelineWorker worker(rig.config, WorkerOptions{}, rig.capture.get(), rig.sinks, &rig.progress);
  worker.start();
  ASSERT_TRUE(wait_frames(worker, 10));
  worker.stop();
  EXPECT_EQ(counting.frames, worker.frames());
  EXPECT_EQ(rig.shm->last_seq(), worker.frames()) << "the shared memory sink saw the same frames";
  EXPECT_GT(counting.valid, 0u);
  EXPECT_EQ(counting.invalid_without_reason, 0u);
  EXPECT_GE(counting.statuses, 1u) << "the final status is always published";
  uint64_t counted = 0;
  for (uint64_t n : counting.last_refusals) counted += n;
  EXPECT_EQ(counted, worker.frames()) << "the last status holds every frame's refusal";
}

// The worker's loop promises no allocation per frame: dequeue, localize,
// every sink (here the shared-memory one) and the status records. A sink
// placed first counts, on the worker thread, from the end of one frame to
// the start of a frame kFrames later.
constexpr uint64_t kWindowFirst = 10, kWindowFrames = 20;

TEST(PipelineWorker, TheFrameLoopAllocatesNothing) {
  struct AllocationWindow final : PublishingSink {
    void consume(const Localization&) override {
      ++frames;
      if (frames == kWindowFirst) test::start_counting_allocations();
      if (frames == kWindowFirst + kWindowFrames) allocations = test::stop_counting_allocations();
    }
    void publish_status(const ServiceStatus&) override {}
    int64_t status_period_ns() const override { return 20'000'000; }
    uint64_t frames = 0;
    long allocations = -1;
  };
  Rig rig;
  AllocationWindow window;
  rig.sinks.insert(rig.sinks.begin(), &window);
  PipelineWorker worker(rig.config, WorkerOptions{}, rig.capture.get(), rig.sinks, &rig.progress);
  worker.start();
  ASSERT_TRUE(wait_frames(worker, kWindowFirst + kWindowFrames + 1));
  worker.stop();
  EXPECT_EQ(window.allocations, 0) << "over " << kWindowFrames << " frames";
}

// Issue 28, defect 4: shared memory and DDS both carry what pose_record_of
// makes; a pose with a non-finite number leaves it as no pose, all zeros.
TEST(PoseRecordOf, ANonFinitePoseLeavesAsNoPoseWithFiniteNumbers) {
  Localization loc;
  loc.published.valid = true;
  loc.published.pose = {1.0, 2.0, 0.3};
  loc.published.covariance = {1e-6, 0, 0, 0, 1e-6, 0, 0, 0, 1e-6};
  PoseRecord good = pose_record_of(loc, 0);
  EXPECT_TRUE(pose_is_valid(good));
  EXPECT_DOUBLE_EQ(good.x_m, 1.0);

  loc.published.covariance[4] = std::nan("");
  PoseRecord bad = pose_record_of(loc, 0);
  EXPECT_FALSE(pose_is_valid(bad));
  EXPECT_TRUE(pose_numbers_finite(bad));

  loc.published.covariance[4] = 1e-6;
  loc.motion.valid = true;
  loc.motion.state.p[40] = std::numeric_limits<double>::infinity();
  bad = pose_record_of(loc, 0);
  EXPECT_FALSE(pose_is_valid(bad));
  EXPECT_TRUE(pose_numbers_finite(bad));
}

}  // namespace
}  // namespace ceilpose::daemon
