// Each kind of bad configuration: its precise message, a non-zero exit, and
// nothing started (no shared-memory segment).
#include <gtest/gtest.h>

#include "core/exit_codes.h"
#include "tests/daemon/daemon_process.h"

namespace ceilpose::test {
namespace {

struct BadConfig {
  const char* name;
  const char* yaml;     // nullptr: the file does not exist
  const char* message;  // expected in stderr, after the file name
};

class DaemonBadConfig : public ::testing::TestWithParam<BadConfig> {
 protected:
  std::string path() {
    const BadConfig& c = GetParam();
    if (c.yaml == nullptr) return ::testing::TempDir() + "does-not-exist.yaml";
    if (std::string(c.name) == "ConfigIsADirectory") return ::testing::TempDir();
    if (std::string(c.name) == "ConfigIsNotARegularFile") return "/dev/zero";
    return write_temp_file("bad.yaml", c.yaml);
  }
};

TEST_P(DaemonBadConfig, CheckConfigNamesTheProblemAndExitsThree) {
  const std::string file = path();
  auto r = run_daemon({"--check-config", file});
  EXPECT_EQ(r.exit.code, ceilpose::kExitBadConfig);
  EXPECT_NE(r.err.find(file + ":"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(GetParam().message), std::string::npos) << r.err;
}

TEST_P(DaemonBadConfig, StartingRefusesBeforeCreatingAnything) {
  const std::string file = path();
  const std::string shm = unique_shm_name();
  auto r = run_daemon({"--config", file, "--shm", shm, "--no-dds"});
  EXPECT_EQ(r.exit.code, ceilpose::kExitBadConfig);
  EXPECT_NE(r.err.find(GetParam().message), std::string::npos) << r.err;
  EXPECT_FALSE(shm_exists(shm)) << "segment created despite a bad configuration";
}

INSTANTIATE_TEST_SUITE_P(
    Kinds, DaemonBadConfig,
    ::testing::Values(
        BadConfig{"SyntaxError", "camera:\n  fx: [530\n", "YAML syntax error"},
        BadConfig{"UnknownKey", "camera:\n  fx: 530\n  fz: 1\n", ":3: unknown key 'camera.fz'"},
        BadConfig{"WrongType", "capture:\n  fps: fast\n",
                  ":2: capture.fps: expected a number, found 'fast'"},
        BadConfig{"OutOfRange", "dds:\n  domain_id: 999\n",
                  ":2: dds.domain_id: expected a value in [0, 230], found '999'"},
        BadConfig{"MissingFile", nullptr, "cannot read configuration file"},
        // Issue 15: windows that accept nothing, a marker larger
        // than its cell, and what used to fail only at start-up.
        BadConfig{"AspectWindowInverted", "detector:\n  aspect_min: 0.9\n  aspect_max: 0.5\n",
                  "detector.aspect_min: expected at most detector.aspect_max = 0.5, "
                  "found 0.9"},
        BadConfig{"FillWindowInverted", "detector:\n  fill_min: 1.5\n  fill_max: 1\n",
                  "detector.fill_min: expected at most detector.fill_max = 1"},
        BadConfig{"AreaWindowInverted", "detector:\n  area_min_ratio: 5\n  area_max_ratio: 2\n",
                  "detector.area_min_ratio: expected at most "
                  "detector.area_max_ratio = 2"},
        BadConfig{"MarkerLargerThanItsCell", "ceiling:\n  rect_width_m: 5\n",
                  "ceiling.rect_width_m: expected a marker"},
        BadConfig{"RobotNameNotARosName", "dds:\n  robot_name: my-robot\n",
                  "dds.robot_name: expected a ROS 2 name token"},
        // Issue 28 #18: one length rule for robot names everywhere.
        BadConfig{"RobotNameLongerThan63Characters",
                  "dds:\n  robot_name: "
                  "rrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrr\n",
                  "dds.robot_name: expected a ROS 2 name token of at most 63 characters"},
        BadConfig{"GroupThatDoesNotExist", "ipc:\n  group: nosuchgroup\n",
                  "ipc.group: expected an existing group"},
        BadConfig{"ShmNameIsADirectory", "ipc:\n  shm_name: /..\n",
                  "ipc.shm_name: expected a shared-memory name"},
        BadConfig{"ShmNameTooLong",
                  "ipc:\n  shm_name: /"
                  "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"
                  "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"
                  "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"
                  "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa\n",
                  "ipc.shm_name: expected a shared-memory name"},
        // The synthetic camera hands frames over as a camera would; it has
        // no JPEG encoder.
        BadConfig{"SyntheticCameraInMjpeg", "capture:\n  pixel_format: mjpeg\n",
                  "capture.pixel_format: expected auto (RGB24) or a format the synthetic "
                  "camera hands over"},
        BadConfig{"ConfigIsADirectory", "", "it is a directory"},
        BadConfig{"ConfigIsNotARegularFile", "", "not a regular file"}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(DaemonCommandLine, ABadMapStopsTheDaemonNamingTheMapAndTheEntry) {
  const std::string map =
      write_temp_file("map.yaml",
                      "format: ceilpose-map\nversion: 1\nmarkers:\n  - code: [9, 1]\n    x_m: 1\n"
                      "    y_m: 1\n");
  const std::string config = write_temp_file("with-map.yaml", "ceiling:\n  map: " + map + "\n");
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"--check-config", config},
        std::vector<std::string>{"--config", config, "--shm", unique_shm_name(), "--no-dds"}}) {
    auto r = run_daemon(args);
    EXPECT_EQ(r.exit.code, ceilpose::kExitBadConfig) << r.err;
    EXPECT_NE(r.err.find(map + ":4: markers[0] (code [9, 1]): code outside the ceiling's 8 x 8"),
              std::string::npos)
        << r.err;
  }
}

TEST(DaemonCommandLine, ValidFileChecksOk) {
  auto r =
      run_daemon({"--check-config", std::string(CEILPOSE_SOURCE_DIR) + "/config/ceilpose.yaml"});
  EXPECT_EQ(r.exit.code, ceilpose::kExitOk) << r.err;
  EXPECT_NE(r.out.find("valid"), std::string::npos);
}

TEST(DaemonCommandLine, UnknownOptionExitsTwo) {
  auto r = run_daemon({"--frobnicate"});
  EXPECT_EQ(r.exit.code, ceilpose::kExitUsage);
}

TEST(DaemonCommandLine, BadOverrideNamesTheOptionAndExitsThree) {
  const std::string shm = unique_shm_name();
  auto r = run_daemon({"--shm", shm, "--domain", "999"});
  EXPECT_EQ(r.exit.code, ceilpose::kExitBadConfig);
  EXPECT_NE(r.err.find("--domain: dds.domain_id"), std::string::npos) << r.err;
  EXPECT_FALSE(shm_exists(shm));
}

TEST(DaemonCommandLine, OptionsOverrideTheFile) {
  const std::string file = write_temp_file("c.yaml", "ipc:\n  shm_name: /from-file\n");
  auto r =
      run_daemon({"--config", file, "--shm", "/from-option", "--robot", "r2", "--print-config"});
  ASSERT_EQ(r.exit.code, ceilpose::kExitOk) << r.err;
  EXPECT_NE(r.out.find("shm_name: \"/from-option\""), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("robot_name: \"r2\""), std::string::npos) << r.out;
}

TEST(DaemonCommandLine, HelpListsTheSpecOptionsAndExitCodes) {
  auto r = run_daemon({"--help"});
  EXPECT_EQ(r.exit.code, ceilpose::kExitOk);
  for (const char* opt : {"--config", "--source", "--robot", "--shm", "--domain", "--duration",
                          "--check-config", "Exit codes"})
    EXPECT_NE(r.out.find(opt), std::string::npos) << opt;
}

}  // namespace
}  // namespace ceilpose::test
