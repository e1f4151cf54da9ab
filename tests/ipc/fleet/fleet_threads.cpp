// The fleet segment with the keeper's thread writing and a controller's
// thread reading at once, in one process so that ThreadSanitizer checks the
// seqlock (fleet_tsan_tests; scripts/test runs it under TSan too): every
// robot a reader sees is whole, one sample's fields together.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <thread>
#include <vector>

#include "ceilpose/pose_client.h"
#include "ipc/shm/shm_fleet_reader.h"
#include "ipc/shm/shm_fleet_writer.h"
#include "tests/ipc/fleet/fleet_test_support.h"

namespace ceilpose {
namespace {

#if defined(__SANITIZE_THREAD__) || defined(__SANITIZE_ADDRESS__)
constexpr uint64_t kUpdates = 20'000;
#else
constexpr uint64_t kUpdates = 400'000;
#endif
constexpr uint32_t kRobots = 8;

// Sample k of robot r: every field says k, so a torn copy shows.
shm::FleetRecord sample(uint32_t r, uint64_t k) {
  shm::FleetRecord rec{};
  std::snprintf(rec.robot, sizeof rec.robot, "r%u", r);
  rec.pose = test::moving_pose(static_cast<int64_t>(k), static_cast<double>(k), k);
  rec.pose.state_covariance[80] = static_cast<double>(k);
  rec.samples = k;
  rec.received_mono_ns = static_cast<int64_t>(k);
  return rec;
}

TEST(FleetThreads, AControllerNeverSeesATornRobotWhileTheKeeperWrites) {
  const std::string shm = test::unique_fleet_shm();
  ShmFleetOptions o;
  o.name = fleet_segment_name(shm);
  o.capacity = kRobots;
  auto writer = ShmFleetWriter::create(o);
  ASSERT_TRUE(writer.ok()) << writer.error().message;
  auto reader = ShmFleetReader::open(shm);
  ASSERT_TRUE(reader.ok()) << reader.error().message;

  std::atomic<bool> done{false};
  std::thread keeper([&] {
    for (uint64_t k = 1; k <= kUpdates; ++k) writer->store(k % kRobots, sample(k % kRobots, k));
    done.store(true, std::memory_order_release);
  });
  std::vector<shm::FleetRecord> out(kRobots);
  uint64_t reads = 0, torn = 0, seen = 0;
  while (!done.load(std::memory_order_acquire) || reads == 0) {
    const uint32_t n = reader->read(0, out.data(), kRobots);
    for (uint32_t i = 0; i < n; ++i) {
      const shm::FleetRecord& r = out[i];
      const auto k = static_cast<double>(r.samples);
      torn += r.pose.x_m != k || r.pose.state_covariance[80] != k || r.pose.seq != r.samples ||
              r.received_mono_ns != static_cast<int64_t>(r.samples);
    }
    seen += n;
    ++reads;
  }
  keeper.join();
  EXPECT_EQ(torn, 0u) << "of " << seen << " robots in " << reads << " snapshots";
  EXPECT_GT(seen, 0u);
  EXPECT_EQ(reader->read(0, out.data(), kRobots), kRobots);
  EXPECT_TRUE(ShmFleetWriter::remove(o.name).ok());
}

}  // namespace
}  // namespace ceilpose
