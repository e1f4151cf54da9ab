// Issue 15: ceilposed in a hostile or broken environment. Each test
// reproduces a probe that once hung, killed or fooled the daemon, and
// asserts the precise message and exit code it gives now.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "core/exit_codes.h"
#include "ipc/shm/shm_pose_writer.h"
#include "tests/daemon/daemon_process.h"

namespace ceilpose::test {
namespace {

constexpr int kBoundMs = 15000;

class DaemonHostile : public ::testing::Test {
 protected:
  void TearDown() override { (void)ShmPoseWriter::remove(shm_); }
  std::vector<std::string> args(std::vector<std::string> extra) const {
    std::vector<std::string> a{"--shm", shm_, "--no-dds"};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  }
  std::string shm_ = unique_shm_name();
};

// A pipe already full, whose reader never reads: before, the first
// --print-poses line blocked the control thread, so --duration, SIGTERM
// and the watchdog were all ignored.
TEST_F(DaemonHostile, AStdoutNobodyReadsNeitherHangsNorStopsTheRun) {
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  fcntl(fds[1], F_SETPIPE_SZ, 4096);
  fcntl(fds[1], F_SETFL, O_NONBLOCK);
  const std::string block(4096, 'x');
  while (write(fds[1], block.data(), block.size()) > 0) {
  }
  fcntl(fds[1], F_SETFL, 0);
  DaemonProcess d(args({"--print-poses", "--duration", "1.5"}), {}, fds[1]);
  const auto exit = d.wait(kBoundMs);
  close(fds[0]);
  close(fds[1]);
  ASSERT_TRUE(exit.has_value()) << "still running " << kBoundMs << " ms into a 1.5 s run";
  EXPECT_TRUE(exit->exited);
  EXPECT_EQ(exit->code, ceilpose::kExitOk) << d.err();
  EXPECT_NE(d.err().find("--print-poses: stdout is not being read; pose lines are dropped"),
            std::string::npos)
      << d.err();
  EXPECT_NE(d.err().find("pose lines dropped because stdout was not read"), std::string::npos)
      << d.err();
}

// `ceilposed ... | head -1`: the reader goes away. Before, SIGPIPE killed
// the daemon (exit 141) and left the segment marked dead.
TEST_F(DaemonHostile, AStdoutClosedByItsReaderEndsThePrintingNotTheDaemon) {
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  close(fds[0]);
  DaemonProcess d(args({"--print-poses", "--duration", "1"}), {}, fds[1]);
  const auto exit = d.wait(kBoundMs);
  close(fds[1]);
  ASSERT_TRUE(exit.has_value());
  EXPECT_TRUE(exit->exited) << "killed by signal " << exit->signal;
  EXPECT_EQ(exit->code, ceilpose::kExitOk) << d.err();
  EXPECT_NE(d.err().find("--print-poses: stdout was closed by its reader after 0 lines"),
            std::string::npos)
      << d.err();
}

TEST_F(DaemonHostile, PrintConfigIntoAFullDeviceFailsAndSaysSo) {
  const int full = open("/dev/full", O_WRONLY | O_CLOEXEC);
  ASSERT_GE(full, 0);
  DaemonProcess d({"--print-config"}, {}, full);
  const auto exit = d.wait(kBoundMs);
  close(full);
  ASSERT_TRUE(exit.has_value());
  EXPECT_EQ(exit->code, ceilpose::kExitFailure);
  EXPECT_NE(d.err().find("ceilposed: cannot write to stdout: No space left on device"),
            std::string::npos)
      << d.err();
}

// `--source "$CAM"` with CAM unset used to publish simulated poses.
TEST_F(DaemonHostile, EmptyOptionValuesAreUsageErrorsNotDefaults) {
  for (const char* option : {"--source", "--shm", "--config", "--robot", "--check-config"}) {
    auto r = run_daemon(args({option, ""}), kBoundMs);
    EXPECT_EQ(r.exit.code, ceilpose::kExitUsage) << option << ": " << r.err;
    EXPECT_NE(r.err.find(std::string(option) + ": must not be empty"), std::string::npos) << r.err;
    EXPECT_FALSE(shm_exists(shm_)) << option;
  }
}

TEST_F(DaemonHostile, ADurationThatWouldNeverEndIsAUsageError) {
  for (const char* value : {"nan", "0", "-1", "inf", "1s"}) {
    auto r = run_daemon(args({"--duration", value}), kBoundMs);
    EXPECT_EQ(r.exit.code, ceilpose::kExitUsage) << value << ": " << r.err;
    EXPECT_NE(r.err.find("--duration: must be a number of seconds above 0, got '" +
                         std::string(value) + "'"),
              std::string::npos)
        << r.err;
  }
}

// A link another user put at the name: exit 5, which the unit does not
// restart (RestartPreventExitStatus), instead of exit 1 every 2 s.
TEST_F(DaemonHostile, ANameTakenInDevShmExitsFiveNamingWhatHoldsIt) {
  const std::string squat = "/dev/shm" + shm_;
  ASSERT_EQ(symlink("/etc/passwd", squat.c_str()), 0);
  auto r = run_daemon(args({"--duration", "1"}), kBoundMs);
  unlink(squat.c_str());
  EXPECT_EQ(r.exit.code, ceilpose::kExitShmNameTaken) << r.err;
  EXPECT_NE(r.err.find(squat + " is a symbolic link owned by uid"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace ceilpose::test
