// How a reader behaves around the writer's life: before it starts, while it
// runs, after it stops, dies or restarts (docs/ipc.md, liveness rules).
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "core/clock.h"
#include "ipc/shm/shm_pose_reader.h"
#include "ipc/shm/shm_pose_writer.h"
#include "shm_test_support.h"

namespace ceilpose {
namespace {

using shm::ShmErrc;
using test::check_pose;
using test::ForkedChild;

class ShmLifecycle : public test::ShmFixture {};

constexpr int kHandshakeMs = 20'000;

// A child that creates a writer, publishes `poses` poses, tells the parent
// and then waits (to be killed, or released to exit cleanly).
ForkedChild::Body publishing_writer(const std::string& name, uint64_t poses) {
  return test::writer_child(name, [poses](ShmPoseWriter& writer, ForkedChild& self) {
    for (uint64_t k = 1; k <= poses; ++k) writer.publish(check_pose(k));
    self.notify_parent();
    self.wait_for_parent(60'000);
    return 0;
  });
}

TEST_F(ShmLifecycle, OpenBeforeWriterStartsReportsNotFound) {
  ShmErrc code = ShmErrc::kOk;
  auto reader = ShmPoseReader::open(name(), &code);
  ASSERT_FALSE(reader);
  EXPECT_EQ(code, ShmErrc::kNotFound);
  EXPECT_NE(reader.error().message.find(name()), std::string::npos) << reader.error().message;
}

TEST_F(ShmLifecycle, ReaderWaitingBeforeWriterStartsAttachesWhenItAppears) {
  std::thread late_writer_starter;
  ForkedChild child([&](ForkedChild& self) {
    if (!self.wait_for_parent(kHandshakeMs)) return 11;
    return publishing_writer(name(), 3)(self);
  });
  // The reader waits first; the writer is released only once it is seen
  // blocked in its wait for the segment.
  const pid_t reader_tid = ::gettid();
  late_writer_starter = std::thread([&] {
    EXPECT_TRUE(test::wait_until_blocked_in(reader_tid, test::poll_syscalls(), kHandshakeMs));
    child.release_child();
  });
  ShmErrc code = ShmErrc::kOk;
  auto reader = ShmPoseReader::open_waiting(name(), 20'000, &code);
  late_writer_starter.join();
  ASSERT_TRUE(reader) << reader.error().message;
  PoseRecord p;
  EXPECT_EQ(reader->wait_next(2, 20'000, &p), WaitResult::kPose);
  EXPECT_EQ(p.seq, 3u);
}

TEST_F(ShmLifecycle, OpenWaitingGivesUpWithNotFoundAfterTimeout) {
  ShmErrc code = ShmErrc::kOk;
  const int64_t start_ns = monotonic_ns();
  auto reader = ShmPoseReader::open_waiting(name(), 200, &code);
  EXPECT_FALSE(reader);
  EXPECT_EQ(code, ShmErrc::kNotFound);
  EXPECT_GE(monotonic_ns() - start_ns, 200'000'000);
}

TEST_F(ShmLifecycle, NewSegmentIsStartingUntilFirstPoseThenLive) {
  ASSERT_NO_FATAL_FAILURE(start());
  PoseRecord p;
  EXPECT_EQ(reader().read_latest(&p), ReadResult::kNoPose);
  EXPECT_EQ(reader().liveness(), Liveness::kStarting);
  writer().publish(check_pose(1));
  EXPECT_EQ(reader().liveness(), Liveness::kLive);
  EXPECT_EQ(reader().writer_info().pid, ::getpid());
  EXPECT_EQ(reader().writer_info().state, WriterState::kRunning);
}

TEST_F(ShmLifecycle, MarkStoppedIsSeenAsStoppedAndSegmentStays) {
  ASSERT_NO_FATAL_FAILURE(start());
  writer().publish(check_pose(1));
  writer().mark_stopped();
  EXPECT_EQ(reader().liveness(), Liveness::kStopped);
  PoseRecord p;
  EXPECT_EQ(reader().wait_next(1, 5'000, &p), WaitResult::kStopped);
  // The last pose stays readable after a clean stop.
  EXPECT_EQ(reader().read_latest(&p), ReadResult::kOk);
  EXPECT_EQ(p.seq, 1u);
}

TEST_F(ShmLifecycle, BlockedReaderReturnsStoppedWhenWriterStops) {
  ASSERT_NO_FATAL_FAILURE(start());
  const pid_t reader_tid = ::gettid();
  std::thread stopper([&] {
    EXPECT_TRUE(test::wait_until_blocked_in(reader_tid, test::futex_syscalls(), kHandshakeMs));
    writer().mark_stopped();
  });
  PoseRecord p;
  EXPECT_EQ(reader().wait_next(0, 20'000, &p), WaitResult::kStopped);
  stopper.join();
}

TEST_F(ShmLifecycle, DestroyingWriterMarksSegmentStopped) {
  ASSERT_NO_FATAL_FAILURE(start());
  writer_.reset();
  EXPECT_EQ(reader().writer_info().state, WriterState::kStopped);
}

TEST_F(ShmLifecycle, HeartbeatOlderThanThresholdIsStale) {
  ASSERT_NO_FATAL_FAILURE(start(/*heartbeat_period_ms=*/0));  // nobody refreshes it
  writer().publish(check_pose(1));
  std::this_thread::sleep_for(std::chrono::milliseconds(120));
  EXPECT_EQ(reader().liveness(100), Liveness::kStale);
  const int64_t before_ns = monotonic_ns();
  writer().heartbeat();
  // The heartbeat is at most (now - before) old; on a loaded machine that can
  // exceed 100 ms, so the threshold allows for it.
  const int64_t allowed_ms = (monotonic_ns() - before_ns) / 1'000'000 + 100;
  EXPECT_EQ(reader().liveness(allowed_ms), Liveness::kLive);
}

TEST_F(ShmLifecycle, HeartbeatThreadKeepsIdleWriterLive) {
  ASSERT_NO_FATAL_FAILURE(start(/*heartbeat_period_ms=*/10));
  const int64_t first_ns = reader().writer_info().heartbeat_mono_ns;
  const int64_t deadline_ns = monotonic_ns() + 20'000'000'000;
  while (reader().writer_info().heartbeat_mono_ns == first_ns && monotonic_ns() < deadline_ns) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_GT(reader().writer_info().heartbeat_mono_ns, first_ns);
}

TEST_F(ShmLifecycle, SecondWriterOnLiveSegmentIsRefusedNamingThePid) {
  ASSERT_NO_FATAL_FAILURE(start());
  ShmOptions options;
  options.name = name();
  ShmErrc code = ShmErrc::kOk;
  auto second = ShmPoseWriter::create(options, &code);
  ASSERT_FALSE(second);
  EXPECT_EQ(code, ShmErrc::kLiveWriter);
  EXPECT_NE(second.error().message.find("pid " + std::to_string(::getpid())), std::string::npos)
      << second.error().message;
  EXPECT_NE(second.error().message.find(name()), std::string::npos);
}

TEST_F(ShmLifecycle, SecondWriterInAnotherProcessIsRefused) {
  ForkedChild child(publishing_writer(name(), 1));
  ASSERT_TRUE(child.wait_for_child(kHandshakeMs));
  ShmOptions options;
  options.name = name();
  ShmErrc code = ShmErrc::kOk;
  auto second = ShmPoseWriter::create(options, &code);
  ASSERT_FALSE(second);
  EXPECT_EQ(code, ShmErrc::kLiveWriter);
  EXPECT_NE(second.error().message.find("pid " + std::to_string(child.pid())), std::string::npos)
      << second.error().message;
}

TEST_F(ShmLifecycle, KilledWriterIsReportedDead) {
  ForkedChild child(publishing_writer(name(), 5));
  ASSERT_TRUE(child.wait_for_child(kHandshakeMs));
  auto reader = ShmPoseReader::open(name());
  ASSERT_TRUE(reader) << reader.error().message;
  EXPECT_EQ(reader->liveness(), Liveness::kLive);
  child.kill_child(SIGKILL);
  ASSERT_EQ(child.wait_exit(20'000), 128 + SIGKILL);
  EXPECT_EQ(reader->liveness(), Liveness::kWriterDead);
  PoseRecord p;
  EXPECT_EQ(reader->wait_next(5, 20'000, &p), WaitResult::kWriterDead);
}

TEST_F(ShmLifecycle, BlockedReaderLearnsThatWriterWasKilled) {
  ForkedChild child(publishing_writer(name(), 1));
  ASSERT_TRUE(child.wait_for_child(kHandshakeMs));
  auto reader = ShmPoseReader::open(name());
  ASSERT_TRUE(reader) << reader.error().message;
  const pid_t reader_tid = ::gettid();
  std::thread killer([&] {
    EXPECT_TRUE(test::wait_until_blocked_in(reader_tid, test::futex_syscalls(), kHandshakeMs));
    child.kill_child(SIGKILL);
    child.wait_exit(20'000);  // reaped: a zombie still answers kill(pid, 0)
  });
  PoseRecord p;
  EXPECT_EQ(reader->wait_next(1, 30'000, &p), WaitResult::kWriterDead);
  killer.join();
}

TEST_F(ShmLifecycle, NewWriterReplacesSegmentOfKilledWriter) {
  ForkedChild child(publishing_writer(name(), 5));
  ASSERT_TRUE(child.wait_for_child(kHandshakeMs));
  auto old_reader = ShmPoseReader::open(name());
  ASSERT_TRUE(old_reader) << old_reader.error().message;
  child.kill_child(SIGKILL);
  ASSERT_EQ(child.wait_exit(20'000), 128 + SIGKILL);

  ShmOptions options;
  options.name = name();
  auto writer = ShmPoseWriter::create(options);
  ASSERT_TRUE(writer) << writer.error().message;
  EXPECT_NE(writer->generation(), old_reader->writer_info().generation);
}

TEST_F(ShmLifecycle, ReaderAcrossWriterRestartSeesRestartedAndReattaches) {
  auto first = std::make_unique<ForkedChild>(publishing_writer(name(), 5));
  ASSERT_TRUE(first->wait_for_child(kHandshakeMs));
  auto reader = ShmPoseReader::open(name());
  ASSERT_TRUE(reader) << reader.error().message;
  const uint64_t old_generation = reader->writer_info().generation;
  PoseRecord p;
  ASSERT_EQ(reader->read_latest(&p), ReadResult::kOk);
  EXPECT_EQ(p.seq, 5u);

  first->release_child();  // clean exit: marks stopped
  ASSERT_EQ(first->wait_exit(20'000), 0);
  EXPECT_EQ(reader->liveness(), Liveness::kStopped);

  ForkedChild second(publishing_writer(name(), 2));
  ASSERT_TRUE(second.wait_for_child(kHandshakeMs));
  EXPECT_EQ(reader->liveness(), Liveness::kRestarted);
  ASSERT_TRUE(reader->reattach());
  EXPECT_NE(reader->writer_info().generation, old_generation);
  EXPECT_EQ(reader->writer_info().pid, second.pid());
  EXPECT_EQ(reader->liveness(), Liveness::kLive);
  ASSERT_EQ(reader->read_latest(&p), ReadResult::kOk);
  EXPECT_EQ(p.seq, 2u);
}

}  // namespace
}  // namespace ceilpose
