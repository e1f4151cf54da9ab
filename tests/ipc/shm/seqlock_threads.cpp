// Concurrency tests that run in one process (two threads on two mappings of
// the same segment), so ThreadSanitizer can check the seqlock and the futex
// hand-off. Built as shm_tsan_tests; scripts/test also runs it under TSan.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "ipc/shm/shm_pose_reader.h"
#include "ipc/shm/shm_pose_writer.h"
#include "shm_test_support.h"

namespace ceilpose {
namespace {

using test::check_pose;
using test::is_consistent;
using test::kSanitizerDivisor;

class ShmSeqlockThreads : public test::ShmFixture {};

// The handshake that proves reads overlapped writes: the writer, halfway,
// waits until the reader has read kWanted times (bounded, so a broken reader
// fails the test instead of hanging it).
struct ReadsSeen {
  static constexpr uint64_t kWanted = 1000;
  std::atomic<uint64_t> reads{0};
  void count(uint64_t n) { reads.store(n, std::memory_order_relaxed); }
  void wait_for_reads() {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (reads.load(std::memory_order_relaxed) < kWanted &&
           std::chrono::steady_clock::now() < deadline)
      std::this_thread::yield();
  }
};

TEST_F(ShmSeqlockThreads, ReaderNeverSeesTornLatestPoseWhileWriterHammers) {
  ASSERT_NO_FATAL_FAILURE(start());

  const uint64_t updates = 2'000'000 / kSanitizerDivisor;
  std::atomic<bool> done{false};
  ReadsSeen seen;
  std::thread writer_thread([&] {
    for (uint64_t k = 1; k <= updates; ++k) {
      writer().publish(check_pose(k));
      if (k == updates / 2) seen.wait_for_reads();
    }
    done.store(true, std::memory_order_release);
  });

  uint64_t reads = 0;
  uint64_t torn = 0;
  uint64_t busy = 0;
  uint64_t went_back = 0;
  uint64_t last = 0;
  PoseRecord p;
  while (!done.load(std::memory_order_acquire)) {
    const ReadResult r = reader().read_latest(&p);
    if (r == ReadResult::kBusy) ++busy;
    if (r != ReadResult::kOk) continue;
    seen.count(++reads);
    if (!is_consistent(p)) ++torn;
    if (p.seq < last) ++went_back;
    last = p.seq;
  }
  writer_thread.join();

  EXPECT_GE(reads, ReadsSeen::kWanted) << "the reader must have read while the writer wrote";
  EXPECT_EQ(torn, 0u) << "of " << reads << " reads";
  EXPECT_EQ(went_back, 0u);
  ASSERT_EQ(reader().read_latest(&p), ReadResult::kOk);
  EXPECT_EQ(p.seq, updates);
  EXPECT_TRUE(is_consistent(p));
  RecordProperty("reads", static_cast<int>(reads));
  RecordProperty("busy", static_cast<int>(busy));
}

TEST_F(ShmSeqlockThreads, RingReadsAreWholeAndNewestFirstWhileWriterHammers) {
  ASSERT_NO_FATAL_FAILURE(start());

  const uint64_t updates = 500'000 / kSanitizerDivisor;
  std::atomic<bool> done{false};
  ReadsSeen seen;
  std::thread writer_thread([&] {
    for (uint64_t k = 1; k <= updates; ++k) {
      writer().publish(check_pose(k));
      if (k == updates / 2) seen.wait_for_reads();
    }
    done.store(true, std::memory_order_release);
  });
  std::vector<PoseRecord> recent(CEILPOSE_POSE_RING_LENGTH);
  uint64_t bad = 0;
  uint64_t reads = 0;
  while (!done.load(std::memory_order_acquire)) {
    const int n = reader().read_recent(recent.data(), static_cast<int>(recent.size()));
    if (n > 0) seen.count(++reads);
    for (int i = 0; i < n; ++i) {
      if (!is_consistent(recent[i])) ++bad;
      if (i > 0 && recent[i].seq + 1 != recent[i - 1].seq) ++bad;
    }
  }
  writer_thread.join();
  EXPECT_GE(reads, ReadsSeen::kWanted) << "the reader must have read while the writer wrote";
  EXPECT_EQ(bad, 0u);
  const int n = reader().read_recent(recent.data(), static_cast<int>(recent.size()));
  ASSERT_EQ(n, CEILPOSE_POSE_RING_LENGTH);
  EXPECT_EQ(recent[0].seq, updates);
  EXPECT_EQ(recent[n - 1].seq, updates - CEILPOSE_POSE_RING_LENGTH + 1);
}

TEST_F(ShmSeqlockThreads, WaitingReaderSeesEveryWakeAsANewerPose) {
  ASSERT_NO_FATAL_FAILURE(start());

  const uint64_t poses = 20'000 / kSanitizerDivisor;
  std::thread writer_thread([&] {
    for (uint64_t k = 1; k <= poses; ++k) {
      writer().publish(check_pose(k));
      if (k % 16 == 0) std::this_thread::yield();  // let the reader block sometimes
    }
  });
  uint64_t last = 0;
  uint64_t inconsistent = 0;
  uint64_t timeouts = 0;
  while (last < poses) {
    PoseRecord p;
    const WaitResult r = reader().wait_next(last, 10'000, &p);
    if (r == WaitResult::kTimeout) {
      ++timeouts;  // a lost wake-up would leave the reader here
      break;
    }
    if (r != WaitResult::kPose) continue;
    if (!is_consistent(p) || p.seq <= last) ++inconsistent;
    last = p.seq;
  }
  writer_thread.join();
  EXPECT_EQ(timeouts, 0u);
  EXPECT_EQ(inconsistent, 0u);
  EXPECT_EQ(last, poses);
}

TEST_F(ShmSeqlockThreads, StatusReadsAreWholeWhileWriterUpdates) {
  ASSERT_NO_FATAL_FAILURE(start());

  const uint64_t updates = 200'000 / kSanitizerDivisor;
  std::atomic<bool> done{false};
  ReadsSeen seen;
  std::thread writer_thread([&] {
    for (uint64_t k = 1; k <= updates; ++k) {
      StatusRecord s{};
      s.frames = k;
      s.drops = 2 * k;
      s.latency_max_us = static_cast<uint32_t>(k);
      s.updated_mono_ns = static_cast<int64_t>(k);
      s.refusal_count = CEILPOSE_REFUSAL_SLOTS;
      for (uint64_t i = 0; i < CEILPOSE_REFUSAL_SLOTS; ++i) s.refusals[i] = k + i;
      set_status_source(&s, (k % 2) != 0 ? "synthetic" : "replay:/data/run");
      writer().update_status(s);
      if (k == updates / 2) seen.wait_for_reads();
    }
    done.store(true, std::memory_order_release);
  });
  uint64_t bad = 0;
  uint64_t reads = 0;
  while (!done.load(std::memory_order_acquire)) {
    StatusRecord s;
    if (reader().read_status(&s) != ReadResult::kOk) continue;
    if (s.frames == 0) continue;
    seen.count(++reads);
    const std::string expected_source = (s.frames % 2) != 0 ? "synthetic" : "replay:/data/run";
    bool whole = s.drops == 2 * s.frames && s.latency_max_us == static_cast<uint32_t>(s.frames) &&
                 expected_source == s.source;
    for (uint64_t i = 0; i < CEILPOSE_REFUSAL_SLOTS; ++i)
      whole = whole && s.refusals[i] == s.frames + i;
    if (!whole) ++bad;
  }
  writer_thread.join();
  EXPECT_GE(reads, ReadsSeen::kWanted) << "the reader must have read while the writer wrote";
  EXPECT_EQ(bad, 0u);
}

}  // namespace
}  // namespace ceilpose
