// Writer and reader in two processes on one segment: the seqlock must hold
// across address spaces (ThreadSanitizer cannot see this; seqlock_threads.cpp
// is the in-process variant it checks).
#include <gtest/gtest.h>

#include "ipc/shm/shm_pose_reader.h"
#include "ipc/shm/shm_pose_writer.h"
#include "shm_test_support.h"

namespace ceilpose {
namespace {

using test::check_pose;
using test::ForkedChild;
using test::is_consistent;
using test::kSanitizerDivisor;
using test::ScopedSegmentName;

constexpr int kHandshakeMs = 20'000;

// Creates the writer, tells the parent, and once released publishes
// check_pose(1..updates) as fast as it can.
ForkedChild::Body hammering_writer(const std::string& name, uint64_t updates) {
  return test::writer_child(name, [updates](ShmPoseWriter& writer, ForkedChild& self) {
    self.notify_parent();
    if (!self.wait_for_parent(kHandshakeMs)) return 11;
    for (uint64_t k = 1; k <= updates; ++k) writer.publish(check_pose(k));
    return 0;
  });
}

TEST(ShmProcessHammer, ReaderProcessNeverSeesTornPoseFromWriterProcess) {
  ScopedSegmentName name;
  const uint64_t updates = 3'000'000 / kSanitizerDivisor;
  ForkedChild child(hammering_writer(name.str(), updates));
  ASSERT_TRUE(child.wait_for_child(kHandshakeMs)) << "writer child did not start";
  auto reader = ShmPoseReader::open(name.str());
  ASSERT_TRUE(reader) << reader.error().message;
  child.release_child();

  uint64_t reads = 0;
  uint64_t torn = 0;
  uint64_t last = 0;
  uint64_t went_back = 0;
  PoseRecord p;
  while (last < updates) {
    if (reader->read_latest(&p) != ReadResult::kOk) {
      if (reader->liveness() == Liveness::kStopped) break;
      continue;
    }
    ++reads;
    if (!is_consistent(p)) ++torn;
    if (p.seq < last) ++went_back;
    last = p.seq;
  }
  EXPECT_EQ(child.wait_exit(60'000), 0);
  EXPECT_EQ(torn, 0u) << "of " << reads << " reads";
  EXPECT_EQ(went_back, 0u);
  EXPECT_EQ(last, updates);
  EXPECT_GT(reads, 0u);
}

TEST(ShmProcessHammer, BlockedReaderProcessGetsPosesInOrderFromWriterProcess) {
  ScopedSegmentName name;
  const uint64_t poses = 50'000 / kSanitizerDivisor;
  ForkedChild child(hammering_writer(name.str(), poses));
  ASSERT_TRUE(child.wait_for_child(kHandshakeMs));
  auto reader = ShmPoseReader::open(name.str());
  ASSERT_TRUE(reader) << reader.error().message;
  child.release_child();

  uint64_t last = 0;
  uint64_t bad = 0;
  WaitResult r = WaitResult::kPose;
  while (last < poses) {
    PoseRecord p;
    r = reader->wait_next(last, 10'000, &p);
    if (r == WaitResult::kBusy) continue;
    if (r != WaitResult::kPose) break;
    if (!is_consistent(p) || p.seq <= last) ++bad;
    last = p.seq;
  }
  EXPECT_EQ(r, WaitResult::kPose) << to_string(r);
  EXPECT_EQ(last, poses);
  EXPECT_EQ(bad, 0u);
  EXPECT_EQ(child.wait_exit(30'000), 0);
}

}  // namespace
}  // namespace ceilpose
