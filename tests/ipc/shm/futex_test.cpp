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

TEST_F(ShmFutex, WaitNextWakesOnPublish) {
  ASSERT_NO_FATAL_FAILURE(start());
  std::thread publisher([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    writer().publish(check_pose(1));
  });
  PoseRecord p;
  EXPECT_EQ(reader().wait_next(0, 30'000, &p), WaitResult::kPose);
  EXPECT_EQ(p.seq, 1u);
  publisher.join();
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
  std::thread waiter([&] {
    PoseRecord p;
    EXPECT_EQ(reader().wait_next(0, 30'000, &p), WaitResult::kPose);
  });
  // Publish only once the waiter is registered: until then wake_syscalls stays 0.
  uint64_t k = 0;
  while (writer().wake_syscalls() == 0 && k < 1'000'000) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    writer().publish(check_pose(++k));
  }
  waiter.join();
  EXPECT_GE(writer().wake_syscalls(), 1u);
}

TEST_F(ShmFutex, ReaderProcessIsWokenByWriterProcess) {
  ForkedChild child(test::writer_child(name(), [](ShmPoseWriter& writer, ForkedChild& self) {
    self.notify_parent();
    if (!self.wait_for_parent(20'000)) return 11;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
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
