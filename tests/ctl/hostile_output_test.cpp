// Issue 15: output that cannot be written is a failure. Every command that
// prints into /dev/full or into a pipe whose reader has gone used to exit 0
// with its output lost.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "core/exit_codes.h"
#include "tests/ctl/run_ceilposectl.h"
#include "tests/recording/recording_test_support.h"

namespace ceilpose::test {
namespace {

class HostileOutput : public ::testing::Test {
 protected:
  void SetUp() override { write_recording(dir_, RecordingSpec{}); }
  std::vector<std::vector<std::string>> printing_commands() const {
    return {{"inspect", dir_},
            {"inspect", dir_, "--json"},
            {"locate", "--replay", dir_},
            {"evaluate", "--replay", dir_},
            {"evaluate", "--replay", dir_, "--json"}};
  }
  TempDir tmp_;
  const std::string dir_ = tmp_.sub("rec");
};

TEST_F(HostileOutput, AFullDeviceIsAFailureThatSaysSo) {
  for (const auto& args : printing_commands()) {
    const int full = open("/dev/full", O_WRONLY | O_CLOEXEC);
    ASSERT_GE(full, 0);
    const CommandOutput r = run_ceilposectl(args, 60'000, full);
    close(full);
    EXPECT_EQ(r.exit_code, kExitFailure) << args[0] << ": " << r.err;
    EXPECT_NE(r.err.find("ceilposectl: cannot write to stdout: No space left on device"),
              std::string::npos)
        << args[0] << ": " << r.err;
  }
}

TEST_F(HostileOutput, AReaderThatWentAwayIsAFailureNotASignal) {
  for (const auto& args : printing_commands()) {
    int fds[2];
    ASSERT_EQ(pipe2(fds, O_CLOEXEC), 0);
    close(fds[0]);
    const CommandOutput r = run_ceilposectl(args, 60'000, fds[1]);
    close(fds[1]);
    EXPECT_EQ(r.exit_code, kExitFailure) << args[0] << " (-1: died of SIGPIPE): " << r.err;
    EXPECT_NE(r.err.find("ceilposectl: cannot write to stdout: Broken pipe"), std::string::npos)
        << args[0] << ": " << r.err;
  }
}

TEST_F(HostileOutput, CountsAndDurationsThatNeverEndAreUsageErrors) {
  const CommandOutput watch = run_ceilposectl({"watch", "--count", "-1"});
  EXPECT_EQ(watch.exit_code, kExitUsage);
  EXPECT_NE(watch.err.find("--count: must be a whole number of at least 0, got '-1'"),
            std::string::npos)
      << watch.err;
  const CommandOutput fleet = run_ceilposectl({"fleet", "--duration", "nan"});
  EXPECT_EQ(fleet.exit_code, kExitUsage);
  EXPECT_NE(fleet.err.find("--duration: must be a number of seconds above 0, got 'nan'"),
            std::string::npos)
      << fleet.err;
}

// Issue 28, defect 8: CLI11's ranges compare, and NaN passes every
// comparison; `record --duration nan` recorded forever, `render --readout-ms
// nan` wrote a recording its own reader rejects. Every floating-point option
// of every sub-command now refuses nan and inf.
TEST_F(HostileOutput, NotANumberOrInfinityIsAUsageErrorInEveryNumericOption) {
  const std::vector<std::vector<std::string>> cases = {
      {"survey", "--prior-sigma-mm", "nan", "--replay", "/nonexistent", "--out", "/tmp/m.yaml"},
      {"render", "--readout-ms", "nan", "--out", "/tmp/ceilpose-nan-render"},
      {"record", "--duration", "inf", "--out", "/tmp/ceilpose-nan-rec", "--source", "synthetic"},
      {"locate", "--predict-ms", "-inf", "--replay", "/nonexistent"},
      {"fleet", "--duration", "nan"}};
  for (const auto& args : cases) {
    const CommandOutput r = run_ceilposectl(args);
    EXPECT_EQ(r.exit_code, kExitUsage) << args[0] << ": " << r.err;
    EXPECT_NE(r.err.find(args[1] + ": "), std::string::npos) << args[0] << ": " << r.err;
  }
}

// Issue 28, defect 20: `--codes 4294967299,5` wrapped to 3 and wrote
// marker_3_5.svg; `--out a/b/c` failed although the help says "created if
// missing".
TEST_F(HostileOutput, MarkerCodesAreReadWholeAndTheOutputDirectoryIsMadeWithItsParents) {
  const CommandOutput wrapped =
      run_ceilposectl({"markers", "--out", "/tmp/ceilpose-wrap", "--codes", "4294967299,5"});
  EXPECT_EQ(wrapped.exit_code, kExitUsage) << wrapped.err;
  EXPECT_NE(wrapped.err.find("'4294967299,5' is outside the ceiling's 0..7 codes"),
            std::string::npos)
      << wrapped.err;
  char tmpl[] = "/tmp/ceilpose-markers-XXXXXX";
  ASSERT_NE(::mkdtemp(tmpl), nullptr);
  const std::string nested = std::string(tmpl) + "/a/b/c";
  const CommandOutput made = run_ceilposectl({"markers", "--out", nested, "--codes", "1,2"});
  EXPECT_EQ(made.exit_code, kExitOk) << made.err;
  EXPECT_TRUE(std::filesystem::exists(nested + "/marker_1_2.svg")) << made.err;
  std::filesystem::remove_all(tmpl);
}

// A malformed --shm used to exit 1 (a runtime failure) from the reader.
TEST_F(HostileOutput, AMalformedShmNameIsAUsageError) {
  for (const char* command : {"pose", "watch", "status"}) {
    for (const char* shm : {"ceilpose", "/a b", "/..", ""}) {
      const CommandOutput r = run_ceilposectl({command, "--shm", shm});
      EXPECT_EQ(r.exit_code, kExitUsage) << command << " --shm '" << shm << "': " << r.err;
      EXPECT_NE(r.err.find("--shm: must be '/' followed by 1-249 printable characters"),
                std::string::npos)
          << command << ": " << r.err;
    }
  }
}

}  // namespace
}  // namespace ceilpose::test
