// Blocking for the next pose: woken by a publish, bounded by the timeout, and
// the writer issues FUTEX_WAKE only when a reader is registered as waiting.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "core/clock.h"
#include "ipc/shm/shm_pose_reader.h"
#include "ipc/shm/shm_pose_writer.h"
#include "shm_test_support.h"

namespace ceilpose {
namespace {

using test::check_pose;
using test::ForkedChild;

class ShmFutex : public test::ShmFixture {};

// The handshake instead of a sleep: true once a reader is registered as
// blocked on `writer` (bounded, so a reader that never blocks fails).
bool until_a_reader_waits(const ShmPoseWriter& writer) {
  const int64_t deadline_ns = monotonic_ns() + 30'000'000'000;
  while (writer.waiting_readers() == 0) {
    if (monotonic_ns() > deadline_ns) return false;
    std::this_thread::yield();
  }
  return true;
}

TEST_F(ShmFutex, WaitNextWakesOnPublish) {
  ASSERT_NO_FATAL_FAILURE(start());
  bool waited = false;
  std::thread publisher([&] {
    waited = until_a_reader_waits(writer());
    writer().publish(check_pose(1));
  });
  PoseRecord p;
  EXPECT_EQ(reader().wait_next(0, 30'000, &p), WaitResult::kPose);
  EXPECT_EQ(p.seq, 1u);
  publisher.join();
  EXPECT_TRUE(waited) << "the reader never registered as blocked";
  // One, or none when the reader's wait returned spuriously just before the
  // publish (seen under qemu): PublishWithBlockedWaiterMakesWakeSyscall
  // holds the writer to the syscall.
  EXPECT_LE(writer().wake_syscalls(), 1u) << "one publish, at most one wake";
  EXPECT_EQ(writer().waiting_readers(), 0u) << "the woken reader deregistered";
}

TEST_F(ShmFutex, WaitNextTimesOutWithoutPublish) {
  ASSERT_NO_FATAL_FAILURE(start());
  PoseRecord p;
  const int64_t start_ns = monotonic_ns();
  EXPECT_EQ(reader().wait_next(0, 150, &p), WaitResult::kTimeout);
  EXPECT_GE(monotonic_ns() - start_ns, 150'000'000);
}

TEST_F(ShmFutex, WaitNextWithZeroTimeoutReturnsAtOnce) {
  ASSERT_NO_FATAL_FAILURE(start());
  PoseRecord p;
  EXPECT_EQ(reader().wait_next(0, 0, &p), WaitResult::kTimeout);
}

TEST_F(ShmFutex, WaitNextReturnsNewestWhenAlreadyNewer) {
  ASSERT_NO_FATAL_FAILURE(start());
  for (uint64_t k = 1; k <= 3; ++k) writer().publish(check_pose(k));
  PoseRecord p;
  EXPECT_EQ(reader().wait_next(1, 0, &p), WaitResult::kPose);
  EXPECT_EQ(p.seq, 3u);
}

TEST_F(ShmFutex, PublishWithoutWaitersMakesNoWakeSyscall) {
  ASSERT_NO_FATAL_FAILURE(start());
  for (uint64_t k = 1; k <= 100; ++k) writer().publish(check_pose(k));
  EXPECT_EQ(writer().wake_syscalls(), 0u);
}

TEST_F(ShmFutex, PublishWithBlockedWaiterMakesWakeSyscall) {
  ASSERT_NO_FATAL_FAILURE(start());
  // A blocked reader's FUTEX_WAIT may return spuriously (EINTR; seen under
  // qemu) and deregister just before the publish reads `waiters`; the reader
  // then finds the pose itself and no wake is due. So a few rounds: a writer
  // that never wakes makes no syscall in any of them.
  constexpr uint64_t kRounds = 5;
  uint64_t rounds = 0;
  while (rounds < kRounds && writer().wake_syscalls() == 0) {
    ++rounds;
    std::thread waiter([&] {
      PoseRecord p;
      EXPECT_EQ(reader().wait_next(rounds - 1, 30'000, &p), WaitResult::kPose);
      EXPECT_EQ(p.seq, rounds);
    });
    // Before the waiter registers, publishing makes no wake syscall.
    EXPECT_EQ(writer().wake_syscalls(), 0u);
    ASSERT_TRUE(until_a_reader_waits(writer()));
    writer().publish(check_pose(rounds));
    waiter.join();
  }
  EXPECT_EQ(writer().wake_syscalls(), 1u)
      << "no publish woke a blocked reader in " << rounds << " rounds";
}

TEST_F(ShmFutex, ReaderProcessIsWokenByWriterProcess) {
  ForkedChild child(test::writer_child(name(), [](ShmPoseWriter& writer, ForkedChild& self) {
    self.notify_parent();
    if (!self.wait_for_parent(20'000)) return 11;
    if (!until_a_reader_waits(writer)) return 13;  // the parent blocks in another process
    writer.publish(check_pose(1));
    return self.wait_for_parent(20'000) ? 0 : 12;
  }));
  ASSERT_TRUE(child.wait_for_child(20'000));
  auto reader = ShmPoseReader::open(name());
  ASSERT_TRUE(reader) << reader.error().message;
  child.release_child();
  PoseRecord p;
  EXPECT_EQ(reader->wait_next(0, 30'000, &p), WaitResult::kPose);
  EXPECT_EQ(p.seq, 1u);
  child.release_child();
  EXPECT_EQ(child.wait_exit(20'000), 0);
}

}  // namespace
}  // namespace ceilpose
