// Each kind of bad configuration gives one precise message: file, line, key
// path, what was expected and what was found.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "config/service_config.h"

namespace ceilpose {
namespace {

using ::testing::HasSubstr;

std::string error_of(const std::string& yaml) {
  auto r = load_config_string(yaml, "test.yaml");
  EXPECT_FALSE(r) << "accepted:\n" << yaml;
  return r ? std::string() : r.error().message;
}

TEST(ConfigLoader, EmptyTextGivesDefaults) {
  auto r = load_config_string("", "empty.yaml");
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(dump_config(*r), dump_config(default_config()));
}

// A text value holding control characters (a double-quoted YAML scalar
// folds an empty line to a line break) is dumped escaped, and reads back
// the same: raw, the break came back as a space (found by fuzz_config).
TEST(ConfigLoader, ATextWithALineBreakDumpsAndLoadsTheSame) {
  const auto r = load_config_string("camera:\n  calibration_file: \"a b\n\n  c\\td\"\n", "t.yaml");
  ASSERT_TRUE(r) << r.error().message;
  const std::string dumped = dump_config(*r);
  EXPECT_NE(dumped.find("\\x0a"), std::string::npos) << dumped;
  const auto again = load_config_string(dumped, "dumped.yaml");
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_EQ(config_values(*again), config_values(*r));
}

TEST(ConfigLoader, KeyOverridesOnlyItself) {
  auto r = load_config_string("camera:\n  fx: 600.5\n", "t.yaml");
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_DOUBLE_EQ(r->pipeline.intrinsics.fx, 600.5);
  EXPECT_DOUBLE_EQ(r->pipeline.intrinsics.fy, 530.0);
}

TEST(ConfigLoader, ReadsEnumsListsAndColours) {
  auto r = load_config_string(
      "positioning:\n  mode: lsq\ndds:\n  reliability: best_effort\n  peers: [a, b]\n"
      "ceiling:\n  red: [1, 2, 3]\nlogging:\n  level: debug\n",
      "t.yaml");
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->pipeline.positioning.mode, PositioningMode::kLeastSquares);
  EXPECT_EQ(r->dds.publisher.reliability, DdsReliability::kBestEffort);
  EXPECT_EQ(r->dds.publisher.domain.peers, (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(r->pipeline.layout.red.g, 2);
  EXPECT_EQ(r->logging.level, LogLevel::kDebug);
}

TEST(ConfigLoader, SyntaxErrorNamesFileLineAndColumn) {
  const std::string e = error_of("camera:\n  fx: [1, 2\n");
  EXPECT_THAT(e, HasSubstr("test.yaml:"));
  EXPECT_THAT(e, HasSubstr("YAML syntax error"));
}

TEST(ConfigLoader, UnknownKeyNamesItsPathAndLine) {
  const std::string e = error_of("camera:\n  fx: 530\n  focal: 3\n");
  EXPECT_THAT(e, HasSubstr("test.yaml:3:"));
  EXPECT_THAT(e, HasSubstr("unknown key 'camera.focal'"));
  EXPECT_THAT(e, HasSubstr("fx"));  // lists what is known
}

TEST(ConfigLoader, UnknownSectionIsAnError) {
  EXPECT_THAT(error_of("kamera:\n  fx: 530\n"), HasSubstr("unknown key 'kamera'"));
}

TEST(ConfigLoader, WrongTypeNamesExpectedAndFound) {
  const std::string e = error_of("camera:\n  fx: fast\n");
  EXPECT_THAT(e, HasSubstr("test.yaml:2: camera.fx: expected a number, found 'fast'"));
}

TEST(ConfigLoader, FractionForIntegerIsAnError) {
  EXPECT_THAT(error_of("capture:\n  buffer_count: 2.5\n"),
              HasSubstr("capture.buffer_count: expected an integer, found '2.5'"));
}

TEST(ConfigLoader, OutOfRangeNamesTheRange) {
  const std::string e = error_of("\ncapture:\n  rt_priority: 120\n");
  EXPECT_THAT(e, HasSubstr("test.yaml:3: capture.rt_priority: expected a value in [0, 99]"));
  EXPECT_THAT(e, HasSubstr("found '120'"));
}

TEST(ConfigLoader, SectionThatIsNotAMappingIsAnError) {
  EXPECT_THAT(error_of("camera: 5\n"), HasSubstr("camera: expected a mapping, found '5'"));
}

TEST(ConfigLoader, YesIsNotABoolean) {
  EXPECT_THAT(error_of("filter:\n  enabled: yes\n"),
              HasSubstr("filter.enabled: expected true or false, found 'yes'"));
}

TEST(ConfigLoader, BadChoiceListsTheChoices) {
  EXPECT_THAT(
      error_of("positioning:\n  mode: magic\n"),
      HasSubstr("positioning.mode: expected one of auto axes barycentric lsq, found 'magic'"));
}

TEST(ConfigLoader, ShortDistortionListIsAnError) {
  EXPECT_THAT(error_of("camera:\n  distortion: [0.1, 0.2]\n"),
              HasSubstr("camera.distortion: expected a list of 5 numbers, found a list"));
}

TEST(ConfigLoader, BadSourceIsAnError) {
  EXPECT_THAT(error_of("capture:\n  source: usb0\n"),
              HasSubstr("capture.source: expected a source: synthetic | replay:DIR"));
}

TEST(ConfigLoader, BadShmNameIsAnError) {
  EXPECT_THAT(error_of("ipc:\n  shm_name: pose/x\n"), HasSubstr("ipc.shm_name: expected"));
}

TEST(ConfigLoader, DuplicateKeyIsAnError) {
  EXPECT_THAT(error_of("camera:\n  fx: 1\n  fx: 2\n"),
              HasSubstr("test.yaml:3: camera.fx: key appears twice"));
}

// Issue 15: 1e300 was accepted and every frame then came out invalid.
TEST(ConfigLoader, ADistortionNoLensCanHaveIsAnError) {
  EXPECT_THAT(error_of("camera:\n  distortion: [1e300, 0, 0, 0, 0]\n"),
              HasSubstr("camera.distortion: expected a lens this camera can have: the distortion "
                        "cannot be inverted at pixel (160, 120)"));
  EXPECT_TRUE(load_config_string("camera:\n  distortion: [-0.35, 0.12, 0, 0, -0.015]\n", "t").ok())
      << "a wide lens is a lens";
}

TEST(ConfigLoader, TheCaptureSizeIsTheCalibrationsNotASecondKey) {
  // The frame size is camera.width x camera.height; a second key could only
  // contradict it.
  EXPECT_THAT(error_of("capture:\n  width_px: 1280\n"),
              HasSubstr("test.yaml:2: unknown key 'capture.width_px'"));
}

TEST(ConfigLoader, SourceGrammarIsCapturesOwn) {
  // The same parser as make_frame_source(): a relative V4L2 path and an empty
  // replay are refused in the file as on the command line.
  for (const char* bad : {"v4l2:video0", "replay:", "libcamera:", "webcam", ""})
    EXPECT_THAT(error_of(std::string("capture:\n  source: \"") + bad + "\"\n"),
                HasSubstr("capture.source: expected a source: synthetic | replay:DIR"))
        << bad;
  for (const char* good : {"v4l2:/tmp/fake-video0", "replay:rec", "libcamera", "libcamera:1"}) {
    auto r = load_config_string(std::string("capture:\n  source: \"") + good + "\"\n", "test.yaml");
    EXPECT_TRUE(r.ok()) << good << ": " << r.error().message;
  }
}

TEST(ConfigLoader, TopLevelListIsAnError) {
  EXPECT_THAT(error_of("- a\n- b\n"), HasSubstr("expected a mapping of sections"));
}

TEST(ConfigLoader, MissingFileNamesThePath) {
  auto r = load_config_file("/nonexistent/ceilpose.yaml");
  ASSERT_FALSE(r);
  EXPECT_THAT(r.error().message,
              HasSubstr("/nonexistent/ceilpose.yaml: cannot read configuration file"));
}

TEST(ConfigLoader, FileErrorsNameTheFile) {
  const std::string path = ::testing::TempDir() + "config_loader_test.yaml";
  std::ofstream(path) << "camera:\n  fy: -3\n";
  auto r = load_config_file(path);
  std::remove(path.c_str());
  ASSERT_FALSE(r);
  EXPECT_THAT(r.error().message, HasSubstr(path + ":2: camera.fy: expected a value in"));
}

TEST(ConfigOverrides, CommandLineValueOverridesFile) {
  auto r = apply_overrides(default_config(), {{"capture.source", "replay:/tmp/rec", "--source"},
                                              {"dds.domain_id", "7", "--domain"}});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->capture.source, "replay:/tmp/rec");
  EXPECT_EQ(r->dds.publisher.domain.domain_id, 7u);
}

TEST(ConfigOverrides, BadValueNamesTheOption) {
  auto r = apply_overrides(default_config(), {{"dds.domain_id", "300", "--domain"}});
  ASSERT_FALSE(r);
  EXPECT_THAT(r.error().message,
              HasSubstr("--domain: dds.domain_id: expected a value in [0, 230]"));
}

TEST(ConfigDiff, NamesExactlyTheChangedKeys) {
  ServiceConfig changed = default_config();
  changed.pipeline.detector.min_rect_area_px += 1;
  changed.capture.device.fps = 60.0;
  EXPECT_EQ(changed_config_keys(default_config(), changed),
            (std::vector<std::string>{"detector.min_rect_area_px", "capture.fps"}));
}

}  // namespace
}  // namespace ceilpose

namespace ceilpose {
namespace {

// Issue 28, defect 6: relative calibration paths resolved against the
// current directory, so another directory's map.yaml was used silently.
TEST(ConfigLoader, RelativeMapAndCameraFilesAreBesideTheConfiguration) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) /
                                    ("ceilpose-relative-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir / "robot");
  const std::filesystem::path file = dir / "robot" / "ceilpose.yaml";
  std::ofstream(file)
      << "camera:\n  calibration_file: cam.yaml\nceiling:\n  map: ../maps/lab.yaml\n";
  auto config = load_config_file(file.string());
  ASSERT_TRUE(config) << config.error().message;
  EXPECT_EQ(config->calibration.camera_file, (dir / "robot" / "cam.yaml").string());
  EXPECT_EQ(config->calibration.map_file, (dir / "maps" / "lab.yaml").string());
  // Absolute paths stay as written.
  std::ofstream(file) << "ceiling:\n  map: /etc/ceilpose/map.yaml\n";
  config = load_config_file(file.string());
  ASSERT_TRUE(config) << config.error().message;
  EXPECT_EQ(config->calibration.map_file, "/etc/ceilpose/map.yaml");
  std::filesystem::remove_all(dir);
}

TEST(ConfigLoader, YamlAliasesAreRefusedNamingTheLine) {
  auto config =
      load_config_string("capture:\n  fps: &f 30\nfleet:\n  history_depth: *f\n", "x.yaml");
  ASSERT_FALSE(config);
  EXPECT_EQ(config.error().message,
            "x.yaml:4: YAML aliases (*name) are not accepted; write the value out");
}

}  // namespace
}  // namespace ceilpose
