// Issue 15: what a hostile local user, a group reader, or the owner's user
// writing over the segment can do, and what the writer and readers do then.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <cstring>
#include <string>

#include "core/clock.h"
#include "ipc/shm/shm_layout.h"
#include "ipc/shm/shm_pose_reader.h"
#include "ipc/shm/shm_pose_writer.h"
#include "shm_test_support.h"

namespace ceilpose {
namespace {

using shm::ShmErrc;

class ShmHostile : public test::ShmFixture {
 protected:
  std::string path(const std::string& name) const { return "/dev/shm" + name; }
  // Writes `bytes` over the start of segment `name` through a mapping of
  // its own, as another process of the owner's user would.
  void scribble(const std::string& name, size_t bytes) {
    const int fd = ::shm_open(name.c_str(), O_RDWR | O_CLOEXEC, 0);
    ASSERT_GE(fd, 0) << name;
    void* p = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    ::close(fd);
    ASSERT_NE(p, MAP_FAILED);
    std::memset(p, 0x5a, bytes);
    ::munmap(p, bytes);
  }
};

// Any user can put a link or a directory at the daemon's name in the
// sticky, world-writable /dev/shm; the writer used to fail with "cannot be
// opened to check its writer" and systemd restarted it every 2 s.
TEST_F(ShmHostile, ALinkOrADirectoryAtTheNameIsRefusedNamingItAndItsOwner) {
  for (const bool directory : {false, true}) {
    for (const std::string& squatted : {name(), shm::wake_segment_name(name())}) {
      if (directory) {
        ASSERT_EQ(::mkdir(path(squatted).c_str(), 0777), 0);
      } else {
        ASSERT_EQ(::symlink("/etc/passwd", path(squatted).c_str()), 0);
      }
      ShmOptions options;
      options.name = name();
      ShmErrc code = ShmErrc::kOk;
      auto writer = ShmPoseWriter::create(options, &code);
      EXPECT_FALSE(writer);
      EXPECT_EQ(code, ShmErrc::kNameTaken);
      if (!writer) {
        const std::string& m = writer.error().message;
        EXPECT_NE(m.find(path(squatted) + " is " + (directory ? "a directory" : "a symbolic link") +
                         " owned by uid " + std::to_string(::geteuid())),
                  std::string::npos)
            << m;
        EXPECT_NE(m.find("remove it (as its owner or root) or choose another ipc.shm_name"),
                  std::string::npos)
            << m;
      }
      directory ? ::rmdir(path(squatted).c_str()) : ::unlink(path(squatted).c_str());
      (void)ShmPoseWriter::remove(name());
    }
  }
}

// A file of another user at the name, its lock held: before, "another
// ceilposed (pid unknown) is publishing". Also what a root-run ceilposed
// leaves behind for the User=ceilpose service.
TEST_F(ShmHostile, AnotherUsersFileWithItsLockHeldIsNamedNotTakenForADaemon) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to make a file of another user";
  const int fd = ::open(path(name()).c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::fchown(fd, 65534, 65534), 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  ShmOptions options;
  options.name = name();
  ShmErrc code = ShmErrc::kOk;
  auto writer = ShmPoseWriter::create(options, &code);
  ::close(fd);
  ASSERT_FALSE(writer);
  EXPECT_EQ(code, ShmErrc::kNameTaken);
  EXPECT_NE(writer.error().message.find(path(name()) + " is a file owned by uid 65534"),
            std::string::npos)
      << writer.error().message;
}

// The -wake segment is read-write for readers (they count themselves in
// it). Four bytes written there by any group reader used to lock out every
// new reader ("-wake does not belong").
TEST_F(ShmHostile, GarbageInTheWakeSegmentLocksNoReaderOut) {
  ASSERT_NO_FATAL_FAILURE(start());
  ASSERT_NO_FATAL_FAILURE(scribble(shm::wake_segment_name(name()), 16));
  ShmErrc code = ShmErrc::kOk;
  auto late = ShmPoseReader::open(name(), &code);
  ASSERT_TRUE(late) << late.error().message;
  writer().publish(test::check_pose(1));
  PoseRecord pose{};
  EXPECT_EQ(late->wait_next(0, 2000, &pose), WaitResult::kPose);
  EXPECT_EQ(pose.seq, 1u);
}

// Garbage over a live segment's header (its owner's user or root): new
// readers said "bad magic" forever and the daemon never noticed. The
// writer owns the header; its heartbeat puts it back and counts it.
TEST_F(ShmHostile, TheWriterRestoresAnOverwrittenHeaderAndCountsIt) {
  ASSERT_NO_FATAL_FAILURE(start(/*heartbeat_period_ms=*/0));
  EXPECT_EQ(writer().header_repairs(), 0u);
  ASSERT_NO_FATAL_FAILURE(scribble(name(), 64));
  ShmErrc code = ShmErrc::kOk;
  EXPECT_FALSE(ShmPoseReader::open(name(), &code)) << "the scribble must break the header";
  EXPECT_EQ(code, ShmErrc::kBadMagic);
  writer().heartbeat();
  EXPECT_EQ(writer().header_repairs(), 1u);
  auto late = ShmPoseReader::open(name(), &code);
  ASSERT_TRUE(late) << late.error().message;
  EXPECT_EQ(late->writer_info().generation, writer().generation());
  writer().heartbeat();
  EXPECT_EQ(writer().header_repairs(), 1u) << "an intact header is not repaired";
}

// truncate(1) of a live segment by its owner or root used to kill the
// daemon and every attached reader with SIGBUS. Now the writer grows the file
// back at its next write and restores the header; a reader that touches the
// lost pages gets zeros instead, sees Liveness::kRestarted and re-attaches.
TEST_F(ShmHostile, ATruncatedSegmentKillsNeitherTheReaderNorTheWriter) {
  ASSERT_NO_FATAL_FAILURE(start(/*heartbeat_period_ms=*/0));
  writer().publish(test::check_pose(1));
  PoseRecord pose{};
  ASSERT_EQ(reader().read_latest(&pose), ReadResult::kOk);
  ASSERT_EQ(::truncate(path(name()).c_str(), 0), 0);

  EXPECT_EQ(reader().read_latest(&pose), ReadResult::kNoPose) << "the lost pages read as zeros";
  EXPECT_TRUE(reader().lost());
  EXPECT_EQ(reader().liveness(500), Liveness::kRestarted);
  EXPECT_EQ(reader().wait_next(1, 2000, &pose), WaitResult::kWriterDead) << "returns at once";

  writer().publish(test::check_pose(2));
  EXPECT_EQ(writer().truncations(), 1u);
  struct stat st {};
  ASSERT_EQ(::stat(path(name()).c_str(), &st), 0);
  EXPECT_EQ(static_cast<size_t>(st.st_size), sizeof(shm::Segment));
  writer().heartbeat();
  EXPECT_GE(writer().header_repairs(), 1u);
  ASSERT_TRUE(reader().reattach()) << "the restored header is valid again";
  EXPECT_FALSE(reader().lost());
  ASSERT_EQ(reader().read_latest(&pose), ReadResult::kOk);
  EXPECT_EQ(pose.seq, 2u);
  EXPECT_EQ(reader().liveness(500), Liveness::kLive);
}

// The -wake companion is what blocked readers count themselves in.
TEST_F(ShmHostile, ATruncatedWakeSegmentKillsNeitherTheReaderNorTheWriter) {
  ASSERT_NO_FATAL_FAILURE(start(/*heartbeat_period_ms=*/0));
  writer().publish(test::check_pose(1));
  ASSERT_EQ(::truncate(path(shm::wake_segment_name(name())).c_str(), 0), 0);
  PoseRecord pose{};
  EXPECT_NE(reader().wait_next(1, 100, &pose), WaitResult::kPose);
  EXPECT_TRUE(reader().lost());
  EXPECT_EQ(reader().liveness(500), Liveness::kRestarted);
  writer().publish(test::check_pose(2));
  EXPECT_EQ(writer().truncations(), 1u);
  writer().heartbeat();
  ASSERT_TRUE(reader().reattach());
  EXPECT_EQ(reader().wait_next(1, 2000, &pose), WaitResult::kPose);
  EXPECT_EQ(pose.seq, 2u);
}

// A SIGBUS that is not about a segment still kills the process, as it would
// without the library's handler.
bool dies_of_sigbus(int status) {
#if defined(__SANITIZE_ADDRESS__)
  // The handler chains to ASan's, which reports the fault and aborts.
  return WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) == 1);
#else
  return WIFSIGNALED(status) && WTERMSIG(status) == SIGBUS;
#endif
}

TEST(ShmSigbusGuard, AFaultOutsideEverySegmentStillKills) {
  // Named here, not in the child: the child dies of its fault, and this
  // process's clean-up unlinks what it created.
  test::ScopedSegmentName other;
  EXPECT_EXIT(
      {
        ShmOptions options;
        options.name = other.str();
        auto writer = ShmPoseWriter::create(options);  // installs the handler
        if (!writer) std::_Exit(3);
        char path[] = "/tmp/ceilpose-sigbus-XXXXXX";
        const int fd = ::mkstemp(path);
        ::unlink(path);
        if (fd < 0 || ::ftruncate(fd, 4096) != 0) std::_Exit(4);
        auto* p = static_cast<volatile char*>(
            ::mmap(nullptr, 4096, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0));
        if (::ftruncate(fd, 0) != 0) std::_Exit(5);
        p[0] = 1;  // past the end of the file
        std::_Exit(0);
      },
      dies_of_sigbus, "");
}

// A file of the right size with no header (zeros: another program's, or a
// writer that died creating it) used to be "not initialized yet: its writer
// is starting" forever, and watch waited on it for good.
TEST_F(ShmHostile, AFileWithoutAHeaderIsForeignOnceNoWriterCanBeCreatingIt) {
  const int fd = ::shm_open(name().c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0640);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::ftruncate(fd, sizeof(shm::Segment)), 0);
  ShmErrc code = ShmErrc::kOk;
  auto fresh = ShmPoseReader::open(name(), &code);
  EXPECT_FALSE(fresh);
  EXPECT_EQ(code, ShmErrc::kNotReady) << "just sized: a writer may be filling it in";
  const timespec ten_s_ago[2] = {{::time(nullptr) - 10, 0}, {::time(nullptr) - 10, 0}};
  ASSERT_EQ(::futimens(fd, ten_s_ago), 0);
  auto old = ShmPoseReader::open(name(), &code);
  ASSERT_FALSE(old);
  EXPECT_EQ(code, ShmErrc::kBadMagic);
  EXPECT_NE(old.error().message.find("shm segment " + name() + " is without a header 1"),
            std::string::npos)
      << old.error().message;
  EXPECT_NE(old.error().message.find(" s after it was sized: not a ceilpose segment"),
            std::string::npos)
      << old.error().message;
  EXPECT_NE(old.error().message.find("remove /dev/shm" + name()), std::string::npos);
  ASSERT_EQ(::ftruncate(fd, 0), 0);
  ASSERT_EQ(::futimens(fd, ten_s_ago), 0);
  auto empty = ShmPoseReader::open(name(), &code);
  ASSERT_FALSE(empty);
  EXPECT_EQ(code, ShmErrc::kBadMagic) << empty.error().message;
  ::close(fd);
}

// A reader in another time namespace (its CLOCK_MONOTONIC behind the
// writer's) used to count the negative age of every heartbeat as live.
TEST_F(ShmHostile, AHeartbeatFromTheFutureIsNotLive) {
  ASSERT_NO_FATAL_FAILURE(start(/*heartbeat_period_ms=*/0));
  writer().publish(test::check_pose(1));
  EXPECT_EQ(reader().liveness(500), Liveness::kLive);
  const int fd = ::shm_open(name().c_str(), O_RDWR | O_CLOEXEC, 0);
  ASSERT_GE(fd, 0);
  void* p = ::mmap(nullptr, sizeof(shm::SegmentHeader), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  ::close(fd);
  ASSERT_NE(p, MAP_FAILED);
  static_cast<shm::SegmentHeader*>(p)->heartbeat_mono_ns.store(monotonic_ns() + 10'000'000'000);
  EXPECT_EQ(reader().liveness(500), Liveness::kStale);
  ::munmap(p, sizeof(shm::SegmentHeader));
}

}  // namespace
}  // namespace ceilpose
