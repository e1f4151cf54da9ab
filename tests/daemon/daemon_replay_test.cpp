// ceilposed on a recording whose camera differs from the configuration's: the
// recording's own camera model (recording.yaml) must be the one localized with,
// as `ceilposectl locate` does.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/exit_codes.h"
#include "core/fix_state.h"
#include "ipc/shm/shm_pose_reader.h"
#include "ipc/shm/shm_pose_writer.h"
#include "recording/recording_writer.h"
#include "sim/renderer.h"
#include "sim/trajectory.h"
#include "tests/daemon/daemon_process.h"

namespace ceilpose::test {
namespace {

// A 320x240 recording of the simulator's trajectory, with ground truth, by
// default under SPEC's ceiling and lens heights.
// Frames from `gap_after` on come an hour later (SPEC §4 allows any gap).
std::string write_small_recording(int frames, double ceiling_height_m = 2.4384,
                                  double lens_height_m = 0.3048, int gap_after = -1) {
  const std::string dir = testing::TempDir() + "ceilposed-replay-" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  sim::SceneOptions scene;
  scene.intrinsics = sim::scaled_default_intrinsics(320);
  scene.layout.height_m = ceiling_height_m;
  CameraMount mount;
  mount.lens_height_m = lens_height_m;
  RecordingCamera camera;
  camera.intrinsics = scene.intrinsics;
  camera.source = "synthetic, daemon_replay_test";
  auto writer = RecordingWriter::create(dir, camera);
  EXPECT_TRUE(writer.ok()) << writer.error().message;
  sim::Renderer renderer(scene);
  Image frame;
  for (int i = 0; i < frames; ++i) {
    const Pose2D truth = sim::trajectory_pose(scene.layout, i / 30.0);
    renderer.render(truth, mount, sim::Effects{}, static_cast<uint64_t>(i), &frame);
    const int64_t gap_ns = gap_after >= 0 && i >= gap_after ? 3'600'000'000'000LL : 0;
    auto r = writer->append(frame.view(), 1'000'000'000 + i * 33'333'333LL + gap_ns, &truth);
    EXPECT_TRUE(r.ok()) << r.error().message;
  }
  EXPECT_TRUE(writer->close().ok());
  return dir;
}

TEST(DaemonReplay, LocalizesWithTheRecordingsCameraNotTheConfiguredOne) {
  ASSERT_EQ(sim::scaled_default_intrinsics(320).width, 320);
  const std::string dir = write_small_recording(30);
  const std::string shm = unique_shm_name();
  // The default configuration describes a 640x480 camera.
  auto r = run_daemon({"--source", "replay:" + dir, "--shm", shm, "--no-dds", "--print-poses",
                       "--duration", "2.5"});
  remove_daemon_segments(shm);
  std::filesystem::remove_all(dir);
  ASSERT_EQ(r.exit.code, ceilpose::kExitOk) << r.err;
  EXPECT_NE(r.err.find("camera model from the recording: 320x240"), std::string::npos) << r.err;
  // --print-poses lines end in "err <position error> mm ...".
  std::istringstream lines(r.out);
  int checked = 0;
  for (std::string line; std::getline(lines, line);) {
    const size_t at = line.find(" err ");
    if (at == std::string::npos) continue;
    ++checked;
    EXPECT_LT(std::strtod(line.c_str() + at + 5, nullptr), 10.0) << line;
  }
  EXPECT_GT(checked, 3) << r.out;
}

// Issue 28, defect 22: a replay's 1 h gap left `status` saying "fix" for as
// long as no frame came, while `pose` said stale.
TEST(DaemonReplay, NoFrameForLongerThanStaleAfterMsIsALostFix) {
  const std::string dir = write_small_recording(20, 2.4384, 0.3048, 10);
  const std::string shm = unique_shm_name();
  auto r = run_daemon({"--source", "replay:" + dir, "--shm", shm, "--no-dds", "--duration", "2.5"});
  std::filesystem::remove_all(dir);
  ASSERT_EQ(r.exit.code, ceilpose::kExitOk) << r.err;
  auto reader = ShmPoseReader::open(shm);
  ASSERT_TRUE(reader) << reader.error().message;
  StatusRecord status{};
  ASSERT_EQ(reader->read_status(&status), ReadResult::kOk);
  remove_daemon_segments(shm);
  EXPECT_EQ(status.frames, 10u);
  EXPECT_EQ(static_cast<FixState>(status.fix_state), FixState::kLost)
      << to_string(static_cast<FixState>(status.fix_state));
}

TEST(DaemonReplay, HeightsTheMarkersContradictGiveNoPoseAndAReasonInTheLog) {
  // Ceiling 3.0 m and lens 0.5 m: 2.5 m to the ceiling where the default
  // configuration says 2.134 m.
  const std::string dir = write_small_recording(30, 3.0, 0.5);
  const std::string shm = unique_shm_name();
  const std::string config = dir + "-config.yaml";
  {
    std::ofstream yaml(config);
    yaml << "logging:\n  problem_report_interval_ms: 300\n";
  }
  auto r = run_daemon({"--config", config, "--source", "replay:" + dir, "--shm", shm, "--no-dds",
                       "--print-poses", "--duration", "2.5"});
  remove_daemon_segments(shm);
  std::filesystem::remove_all(dir);
  std::filesystem::remove(config);
  ASSERT_EQ(r.exit.code, ceilpose::kExitOk) << r.err;
  EXPECT_NE(r.err.find("frames refused because the markers' spacing contradicts the configured "
                       "heights (check ceiling.height_m and mount.lens_height_m)"),
            std::string::npos)
      << r.err;
  // Frames were processed, and no pose was made up: --print-poses shows
  // "no pose" lines and no position error column.
  EXPECT_NE(r.out.find("no pose"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find(" err "), std::string::npos) << r.out;
}

}  // namespace
}  // namespace ceilpose::test
