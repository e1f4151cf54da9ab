// `ceilposectl render` end to end: the recording it writes reads back with
// the scenario's ground truth and the renderer's exact pixels.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "recording/recording_reader.h"
#include "sim/renderer.h"
#include "sim/scenarios.h"

namespace ceilpose::sim {
namespace {

namespace fs = std::filesystem;

struct CtlRun {
  int exit_code = -1;
  std::string out, err;
};

class RenderCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char templ[] = "/tmp/ceilpose_render_test_XXXXXX";
    ASSERT_NE(::mkdtemp(templ), nullptr);
    dir_ = templ;
  }
  void TearDown() override { fs::remove_all(dir_); }

  CtlRun ctl(const std::string& args) const {
    const std::string out = dir_ + "/stdout", err = dir_ + "/stderr";
    const std::string cmd = std::string(CEILPOSECTL_PATH) + " " + args + " >" + out + " 2>" + err;
    const int status = std::system(cmd.c_str());
    CtlRun r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
  }
  static std::string slurp(const std::string& path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }

  std::string dir_;
};

TEST_F(RenderCommandTest, WritesARecordingThatReadsBackWithGroundTruthAndExactPixels) {
  const std::string rec = dir_ + "/rec";
  const CtlRun r = ctl("render --scenario thesis_points --frames 5 --seed 4 --out " + rec);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  Result<RecordingReader> reader = RecordingReader::open(rec);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  SceneOptions options;
  options.seed = 4;
  const Result<Scenario> scenario = make_scenario("thesis_points", options, 5, 4);
  ASSERT_TRUE(scenario.ok());
  ASSERT_EQ(reader->rows().size(), 5u);
  Renderer renderer(options);
  for (size_t i = 0; i < 5; ++i) {
    const RecordingRow& row = reader->rows()[i];
    const ScenarioFrame& f = scenario->frames[i];
    ASSERT_TRUE(row.has_ground_truth);
    EXPECT_NEAR(row.ground_truth.x_m, f.pose.x_m, 1e-9);
    EXPECT_NEAR(row.ground_truth.y_m, f.pose.y_m, 1e-9);
    EXPECT_NEAR(row.ground_truth.yaw_rad, f.pose.yaw_rad, 1e-9);
    EXPECT_EQ(row.timestamp_ns, f.timestamp_ns);
    Image stored, rendered;
    ASSERT_TRUE(reader->load_frame(i, &stored).ok());
    renderer.render(f.pose, f.mount, f.effects, f.seed, &rendered);
    ASSERT_EQ(stored.size_bytes(), rendered.size_bytes());
    EXPECT_EQ(std::memcmp(stored.data(), rendered.data(), stored.size_bytes()), 0) << "frame " << i;
  }
}

TEST_F(RenderCommandTest, ConfigurationSetsTheCameraAndMountOfTheRecording) {
  std::ofstream(dir_ + "/cfg.yaml") << "camera:\n  distortion: [-0.1, 0.02, 0.0, 0.0, 0.0]\n"
                                       "mount:\n  offset_forward_m: 0.05\n  yaw_rad: 0.3\n";
  const std::string rec = dir_ + "/rec";
  const CtlRun r = ctl("render --scenario random --frames 2 --seed 6 --config " + dir_ +
                       "/cfg.yaml --out " + rec);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  Result<RecordingReader> reader = RecordingReader::open(rec);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  SceneOptions options;
  options.seed = 6;
  options.intrinsics.distortion = {-0.1, 0.02, 0.0, 0.0, 0.0};
  EXPECT_EQ(reader->camera().intrinsics.distortion, options.intrinsics.distortion);
  CameraMount mount;
  mount.offset_forward_m = 0.05;
  mount.yaw_rad = 0.3;
  const Result<Scenario> scenario = make_scenario("random", options, 2, 6);
  ASSERT_TRUE(scenario.ok());
  Renderer renderer(options);
  Image stored, rendered;
  ASSERT_TRUE(reader->load_frame(1, &stored).ok());
  const ScenarioFrame& f = scenario->frames[1];
  renderer.render(f.pose, mount, f.effects, f.seed, &rendered);
  ASSERT_EQ(stored.size_bytes(), rendered.size_bytes());
  EXPECT_EQ(std::memcmp(stored.data(), rendered.data(), stored.size_bytes()), 0);
}

TEST_F(RenderCommandTest, MalformedConfigurationIsABadInputError) {
  std::ofstream(dir_ + "/cfg.yaml") << "camera:\n  fx: [oops\n";
  const CtlRun r =
      ctl("render --scenario random --config " + dir_ + "/cfg.yaml --out " + dir_ + "/rec");
  EXPECT_EQ(r.exit_code, 4);
  EXPECT_NE(r.err.find("cfg.yaml"), std::string::npos);
}

TEST_F(RenderCommandTest, UnknownScenarioIsAUsageErrorThatNamesIt) {
  const CtlRun r = ctl("render --scenario nonsense --out " + dir_ + "/rec");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("nonsense"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir_ + "/rec"));
}

TEST_F(RenderCommandTest, RefusesANonEmptyOutputDirectory) {
  std::ofstream(dir_ + "/keep.txt") << "x";
  const CtlRun r = ctl("render --scenario random --frames 1 --out " + dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(dir_), std::string::npos);
}

TEST_F(RenderCommandTest, ListAndHelpNameEveryScenario) {
  const CtlRun list = ctl("render --list");
  const CtlRun help = ctl("render --help");
  EXPECT_EQ(list.exit_code, 0);
  EXPECT_EQ(help.exit_code, 0);
  for (const auto& [name, description] : scenario_catalog()) {
    EXPECT_NE(list.out.find(name), std::string::npos) << name;
    EXPECT_NE(help.out.find(description), std::string::npos) << name;
  }
}

}  // namespace
}  // namespace ceilpose::sim
