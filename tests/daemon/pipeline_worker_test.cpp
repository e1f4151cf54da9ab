// The pipeline thread against a real capture thread (synthetic source) and a
// real shared-memory writer, while the control thread reads snapshots and
// reloads the configuration: the concurrency the daemon lives with. Runs
// under ThreadSanitizer (label tsan).
#include "daemon/pipeline_worker.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "capture/capture_thread.h"
#include "capture/frame_source.h"
#include "ipc/shm/shm_pose_reader.h"
#include "ipc/shm/shm_pose_writer.h"

namespace ceilpose::daemon {
namespace {

struct Rig {
  Rig() {
    capture::SourceOptions so;
    so.intrinsics = config.pipeline.intrinsics;
    so.layout = config.pipeline.layout;
    so.mount = config.pipeline.mount;
    so.fps = 30.0;
    auto source = capture::make_frame_source("synthetic", so);
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
  ProblemCounters problems;
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
  PipelineWorker worker(rig.config, WorkerOptions{}, rig.capture.get(), &*rig.shm, nullptr,
                        &rig.problems, &rig.progress);
  worker.start();
  ASSERT_TRUE(wait_frames(worker, 10));
  worker.stop();
  EXPECT_EQ(rig.shm->last_seq(), worker.frames());
  EXPECT_EQ(rig.progress.count(), worker.frames());
  EXPECT_EQ(worker.latency().dequeue_to_published().count(), worker.frames());
  EXPECT_FALSE(worker.finished()) << "stopped on request, not by the source";
}

TEST(PipelineWorker, SnapshotsAndReloadsFromAnotherThreadKeepTheSequenceRising) {
  Rig rig;
  PipelineWorker worker(rig.config, WorkerOptions{}, rig.capture.get(), &*rig.shm, nullptr,
                        &rig.problems, &rig.progress);
  worker.start();
  ASSERT_TRUE(wait_frames(worker, 2));
  uint64_t last_seq = 0;
  ServiceConfig changed = rig.config;
  for (int i = 0; i < 30; ++i) {
    changed.pipeline.detector.min_rect_area_px = (i % 2 == 0) ? 1 << 23 : 150;
    worker.reload(changed, i % 3 == 0);
    const PoseSnapshot s = worker.latest();
    EXPECT_GE(s.seq, last_seq);
    last_seq = s.seq;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const uint64_t before = worker.frames();
  ASSERT_TRUE(wait_frames(worker, before + 5)) << "stream stopped after reloads";
  worker.stop();
  EXPECT_EQ(rig.shm->last_seq(), worker.frames());
}

TEST(PipelineWorker, StatusRecordReachesReaders) {
  Rig rig;
  WorkerOptions options;
  options.status_interval_ms = 50;
  PipelineWorker worker(rig.config, options, rig.capture.get(), &*rig.shm, nullptr, &rig.problems,
                        &rig.progress);
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
}

}  // namespace
}  // namespace ceilpose::daemon
