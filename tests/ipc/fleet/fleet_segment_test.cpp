// The fleet segment as a hostile or careless world leaves it: a second
// daemon, foreign files at the name, another ABI, a keeper that died; and
// the reads a controller makes every cycle allocate nothing.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstring>
#include <deque>
#include <string>
#include <vector>

#include "ceilpose/pose_client.h"
#include "core/clock.h"
#include "ipc/fleet/fleet_keeper.h"
#include "ipc/shm/shm_fleet_reader.h"
#include "ipc/shm/shm_fleet_writer.h"
#include "tests/ipc/fleet/fleet_test_support.h"
#include "tests/support/alloc_count.h"

namespace ceilpose {
namespace {

using test::kMs;

ShmFleetWriter make_writer(const std::string& shm, uint32_t capacity = 8) {
  ShmFleetOptions o;
  o.name = fleet_segment_name(shm);
  o.capacity = capacity;
  o.stale_after_ms = 500;
  auto w = ShmFleetWriter::create(o);
  EXPECT_TRUE(w.ok()) << w.error().message;
  return std::move(w).value();
}

// Writes `bytes` as the whole content of the shm file `name`.
void write_foreign(const std::string& name, const void* bytes, size_t size) {
  const int fd = ::shm_open(name.c_str(), O_RDWR | O_CREAT | O_TRUNC, 0600);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::write(fd, bytes, size), static_cast<ssize_t>(size));
  ::close(fd);
}

TEST(FleetSegment, ASecondDaemonCannotTakeALiveFleetSegment) {
  const std::string shm = test::unique_fleet_shm();
  ShmFleetWriter first = make_writer(shm);
  ShmFleetOptions o;
  o.name = fleet_segment_name(shm);
  shm::ShmErrc code = shm::ShmErrc::kOk;
  auto second = ShmFleetWriter::create(o, &code);
  ASSERT_FALSE(second.ok());
  EXPECT_EQ(code, shm::ShmErrc::kLiveWriter);
  EXPECT_NE(second.error().message.find(std::to_string(::getpid())), std::string::npos)
      << second.error().message;
  EXPECT_TRUE(ShmFleetWriter::remove(first.name()).ok());
}

TEST(FleetSegment, CapacityOutOfRangeIsRefusedNamingTheLimit) {
  ShmFleetOptions o;
  o.name = fleet_segment_name(test::unique_fleet_shm());
  for (uint32_t capacity : {0u, 1'000'000u}) {
    o.capacity = capacity;
    auto w = ShmFleetWriter::create(o);
    ASSERT_FALSE(w.ok());
    EXPECT_NE(w.error().message.find("capacity must be 1..65536"), std::string::npos)
        << w.error().message;
  }
}

TEST(FleetSegment, ReadersRefuseForeignFilesAndOtherAbisByName) {
  const std::string shm = test::unique_fleet_shm();
  const std::string name = fleet_segment_name(shm);
  ceilpose_fleet* f = nullptr;
  EXPECT_EQ(ceilpose_client_fleet_open(shm.c_str(), &f), CEILPOSE_ERR_NOT_FOUND);
  EXPECT_NE(std::string(ceilpose_last_error_message()).find(name), std::string::npos);

  char tiny[16] = "not a segment";
  write_foreign(name, tiny, sizeof tiny);
  EXPECT_EQ(ceilpose_client_fleet_open(shm.c_str(), &f), CEILPOSE_ERR_BAD_SIZE);
  EXPECT_NE(std::string(ceilpose_last_error_message()).find("too small"), std::string::npos)
      << ceilpose_last_error_message();

  // A header of the right size with another magic, then another ABI.
  std::vector<char> bytes(shm::fleet_segment_size(1), 0);
  std::memcpy(bytes.data(), "NOTCEILP", 8);
  write_foreign(name, bytes.data(), bytes.size());
  EXPECT_EQ(ceilpose_client_fleet_open(shm.c_str(), &f), CEILPOSE_ERR_BAD_MAGIC);
  auto* h = reinterpret_cast<shm::FleetHeader*>(bytes.data());
  h->magic.store(shm::kFleetMagic);
  h->abi_version = 99;
  write_foreign(name, bytes.data(), bytes.size());
  EXPECT_EQ(ceilpose_client_fleet_open(shm.c_str(), &f), CEILPOSE_ERR_ABI_MISMATCH);
  EXPECT_NE(std::string(ceilpose_last_error_message()).find("fleet ABI version 99"),
            std::string::npos)
      << ceilpose_last_error_message();
  // The right ABI but a capacity the file cannot hold.
  h->abi_version = shm::kFleetAbiVersion;
  h->header_size = sizeof(shm::FleetHeader);
  h->slot_size = sizeof(shm::FleetSlot);
  h->capacity = 1000;
  h->segment_size = bytes.size();
  write_foreign(name, bytes.data(), bytes.size());
  EXPECT_EQ(ceilpose_client_fleet_open(shm.c_str(), &f), CEILPOSE_ERR_BAD_SIZE);
  EXPECT_EQ(f, nullptr);
  ::shm_unlink(name.c_str());
  EXPECT_EQ(ceilpose_client_fleet_open(nullptr, nullptr), CEILPOSE_ERR_INVALID_ARGUMENT);
  uint32_t n = 0;
  EXPECT_EQ(ceilpose_client_fleet_read(nullptr, 0, nullptr, 0, &n), CEILPOSE_ERR_INVALID_ARGUMENT);
}

TEST(FleetSegment, ReadersCallARobotStaleWhenNothingCameForItsLimitWhateverTheKeeperSaid) {
  // A keeper that died marks nothing stale any more; readers judge the age.
  const std::string shm = test::unique_fleet_shm();
  ShmFleetWriter w = make_writer(shm);
  shm::FleetRecord fresh{};
  std::strcpy(fresh.robot, "fresh");
  fresh.pose = test::moving_pose(realtime_ns(), 1.0);
  fresh.received_mono_ns = monotonic_ns();
  shm::FleetRecord old = fresh;
  std::strcpy(old.robot, "old");
  old.received_mono_ns = monotonic_ns() - 2000 * kMs;
  w.store(0, fresh);
  w.store(1, old);
  auto reader = ShmFleetReader::open(shm);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  shm::FleetRecord out[4];
  ASSERT_EQ(reader->read(0, out, 4), 2u);
  EXPECT_FALSE(out[0].fleet_flags & CEILPOSE_FLEET_STALE);
  EXPECT_TRUE(out[1].fleet_flags & CEILPOSE_FLEET_STALE);
  w.clear(0);
  ASSERT_EQ(reader->read(0, out, 4), 1u);
  EXPECT_STREQ(out[0].robot, "old");
  EXPECT_EQ(reader->info().robots, 1u);
  EXPECT_TRUE(ShmFleetWriter::remove(w.name()).ok());
}

// Garbage over a live fleet segment's header, or truncate(1) (its owner's
// user or root): controllers' new opens said "bad magic" or "too small"
// for as long as the daemon ran. The writer's heartbeat restores the header
// and counts it, as the pose segment's writer does.
TEST(FleetSegment, TheWriterRestoresAnOverwrittenOrTruncatedHeaderAndCountsIt) {
  const std::string shm = test::unique_fleet_shm();
  ShmFleetWriter w = make_writer(shm);
  w.mark_running();
  shm::FleetRecord robot{};
  std::strcpy(robot.robot, "r1");
  robot.pose = test::moving_pose(realtime_ns(), 1.0);
  robot.received_mono_ns = monotonic_ns();
  w.store(0, robot);

  const std::string name = fleet_segment_name(shm);
  const int fd = ::shm_open(name.c_str(), O_RDWR, 0);
  ASSERT_GE(fd, 0);
  void* p = ::mmap(nullptr, sizeof(shm::FleetHeader), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  ASSERT_NE(p, MAP_FAILED);
  std::memset(p, 0x5a, sizeof(shm::FleetHeader));
  ::munmap(p, sizeof(shm::FleetHeader));
  EXPECT_FALSE(ShmFleetReader::open(shm).ok()) << "the scribble must break the header";
  w.heartbeat();
  EXPECT_EQ(w.header_repairs(), 1u);
  auto reader = ShmFleetReader::open(shm);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  shm::FleetRecord out[2];
  ASSERT_EQ(reader->read(0, out, 2), 1u) << "slots and counts as the writer keeps them";
  EXPECT_STREQ(out[0].robot, "r1");
  w.heartbeat();
  EXPECT_EQ(w.header_repairs(), 1u) << "an intact header is not repaired";

  ASSERT_EQ(::ftruncate(fd, 0), 0);
  ::close(fd);
  w.store(0, robot);  // the keeper's next sample: grows the file back
  w.heartbeat();
  EXPECT_EQ(w.truncations(), 1u);
  EXPECT_EQ(w.header_repairs(), 2u);
  auto again = ShmFleetReader::open(shm);
  ASSERT_TRUE(again.ok()) << again.error().message;
  ASSERT_EQ(again->read(0, out, 2), 1u);
  EXPECT_STREQ(out[0].robot, "r1");
  EXPECT_TRUE(ShmFleetWriter::remove(w.name()).ok());
}

TEST(FleetSegment, AControllersReadAndTheKeepersKnownRobotAllocateNothing) {
  const std::string shm = test::unique_fleet_shm();
  ShmFleetWriter w = make_writer(shm, 64);
  FleetKeeper keeper(&w, FleetOptions{}, nullptr);
  std::deque<std::string> names;
  for (int i = 0; i < 50; ++i) names.push_back("robot" + std::to_string(i));
  auto give = [&](int i, int64_t at_ns) {
    FleetSample s;
    s.robot = &names[i];
    s.writer = 100 + i;
    s.pose = test::moving_pose(realtime_ns() - 5 * kMs, i * 0.1, at_ns);
    keeper.on_sample(s);
  };
  for (int i = 0; i < 50; ++i) give(i, 1);
  ceilpose_fleet* f = nullptr;
  ASSERT_EQ(ceilpose_client_fleet_open(shm.c_str(), &f), CEILPOSE_OK);
  std::vector<ceilpose_fleet_robot> out(64);
  uint32_t n = 0;
  test::start_counting_allocations();
  for (int i = 0; i < 50; ++i) give(i, 2);
  keeper.sweep(monotonic_ns());
  ceilpose_client_fleet_read(f, monotonic_ns(), out.data(), 64, &n);
  ceilpose_fleet_robot one{};
  ceilpose_client_fleet_find(f, "robot7", monotonic_ns(), &one);
  EXPECT_EQ(test::stop_counting_allocations(), 0);
  EXPECT_EQ(n, 50u);
  EXPECT_TRUE(one.fleet_flags & CEILPOSE_FLEET_PREDICTED);
  ceilpose_client_fleet_close(f);
  EXPECT_TRUE(ShmFleetWriter::remove(w.name()).ok());
}

}  // namespace
}  // namespace ceilpose
