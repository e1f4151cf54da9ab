// `ceilposectl locate` and `ceilposectl evaluate` end to end on a small
// rendered recording: the JSON Lines of SPEC §5, and the exit codes.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/exit_codes.h"
#include "recording/recording_writer.h"
#include "sim/renderer.h"

namespace ceilpose {
namespace {

namespace fs = std::filesystem;

// Built before this test (tests/pipeline/CMakeLists.txt depends on it).
fs::path ctl_binary() { return CEILPOSECTL_PATH; }

struct CommandRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

class LocateCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/ceilpose_locate_XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }

  // `shell_prefix`: shell commands run first, e.g. "ulimit -v 700000; ".
  CommandRun run(const std::string& args, const std::string& shell_prefix = "") {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string cmd = shell_prefix + "exec " + ctl_binary().string() + " " + args + " >" +
                            out.string() + " 2>" + err.string() + " </dev/null";
    const int status = std::system(cmd.c_str());
    CommandRun r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
  }
  static std::string slurp(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

  // Renders the poses into a recording with ground truth, by default under
  // SPEC's ceiling and camera heights.
  fs::path record(const std::vector<Pose2D>& poses, double ceiling_height_m = 2.4384,
                  double lens_height_m = 0.3048) {
    const fs::path rec = dir_ / "rec";
    sim::SceneOptions options;
    options.layout.height_m = ceiling_height_m;
    CameraMount mount;
    mount.lens_height_m = lens_height_m;
    sim::Renderer renderer(options);
    auto writer =
        RecordingWriter::create(rec.string(), RecordingCamera{options.intrinsics, "test"});
    EXPECT_TRUE(writer.ok()) << writer.error().message;
    Image image;
    for (size_t k = 0; k < poses.size(); ++k) {
      sim::Effects effects;
      effects.read_noise_sigma = 2.0;
      renderer.render(poses[k], mount, effects, k + 1, &image);
      auto appended =
          writer->append(image.view(), 1'000'000'000 + 33'333'333 * int64_t(k), &poses[k]);
      EXPECT_TRUE(appended.ok()) << appended.error().message;
    }
    EXPECT_TRUE(writer->close().ok());
    return rec;
  }

  std::string rec_of(const std::vector<Pose2D>& poses) { return record(poses).string(); }

  fs::path dir_;
};

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream s(text);
  for (std::string line; std::getline(s, line);) out.push_back(line);
  return out;
}

// The number after "key": in a flat JSON object (NaN when absent or null).
double field(const std::string& line, const std::string& key) {
  const size_t at = line.find("\"" + key + "\":");
  if (at == std::string::npos) return NAN;
  const std::string rest = line.substr(at + key.size() + 3);
  if (rest.rfind("null", 0) == 0) return NAN;
  return std::strtod(rest.c_str(), nullptr);
}

TEST_F(LocateCommand, PrintsOneSpecJsonLinePerFrameWithAccuratePoses) {
  // The last pose is far off the grid: nothing in view.
  const std::vector<Pose2D> poses{
      {1.2, 1.5, 0.3}, {2.0, 2.2, -2.0}, {3.0, 1.0, 1.6}, {-20.0, -20.0, 0.0}};
  const fs::path rec = record(poses);
  const CommandRun r = run("locate --replay " + rec.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto out = lines(r.out);
  ASSERT_EQ(out.size(), poses.size());
  for (size_t k = 0; k + 1 < poses.size(); ++k) {
    const std::string& l = out[k];
    EXPECT_EQ(field(l, "index"), static_cast<double>(k));
    EXPECT_EQ(field(l, "timestamp_ns"), 1e9 + 33'333'333.0 * k);
    EXPECT_NE(l.find("\"valid\":true"), std::string::npos) << l;
    EXPECT_NEAR(field(l, "x_m"), poses[k].x_m, 0.005) << l;
    EXPECT_NEAR(field(l, "y_m"), poses[k].y_m, 0.005) << l;
    EXPECT_NEAR(field(l, "yaw_rad"), poses[k].yaw_rad, 0.01) << l;
    EXPECT_NE(l.find("\"mode\":\"lsq\""), std::string::npos) << l;
    EXPECT_GE(field(l, "markers"), 3.0) << l;
    EXPECT_GE(field(l, "proc_us"), 0.0) << l;
    EXPECT_NE(l.find("\"refusal\":null"), std::string::npos) << l;
  }
  const std::string& off = out.back();
  EXPECT_NE(off.find("\"valid\":false,\"x_m\":null,\"y_m\":null,\"yaw_rad\":null"),
            std::string::npos)
      << off;
  EXPECT_NE(off.find("\"refusal\":\"no_markers\""), std::string::npos) << off;
  EXPECT_TRUE(r.err.empty()) << "stderr is not a terminal: no progress expected: " << r.err;
}

TEST_F(LocateCommand, ForcedModeIsReportedAndFilterKeepsEveryFrame) {
  const fs::path rec = record({{1.2, 1.5, 0.3}, {1.21, 1.5, 0.3}, {1.22, 1.5, 0.3}});
  CommandRun r = run("locate --mode axes --replay " + rec.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const auto& l : lines(r.out)) EXPECT_NE(l.find("\"mode\":\"axes\""), std::string::npos);
  r = run("locate --filter --replay " + rec.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto out = lines(r.out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_NEAR(field(out[2], "x_m"), 1.22, 0.01);
}

// SPEC §5: --filter adds the velocity; --predict-ms MS gives the pose MS past
// each frame and echoes MS. A robot driving East at 0.6 m/s.
TEST_F(LocateCommand, FilterGivesVelocityAndPredictMsThePoseAhead) {
  std::vector<Pose2D> poses;
  for (int k = 0; k < 30; ++k) poses.push_back({1.0 + 0.02 * k, 1.5, 0.0});
  const fs::path rec = record(poses);
  CommandRun r = run("locate --replay " + rec.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.find("vx_mps"), std::string::npos) << "per frame: no velocity";
  r = run("locate --filter --replay " + rec.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto out = lines(r.out);
  ASSERT_EQ(out.size(), poses.size());
  EXPECT_NEAR(field(out.back(), "vx_mps"), 0.6, 0.01) << out.back();
  EXPECT_NEAR(field(out.back(), "vy_mps"), 0.0, 0.01) << out.back();
  EXPECT_NEAR(field(out.back(), "yaw_rate_radps"), 0.0, 0.01) << out.back();
  EXPECT_TRUE(std::isnan(field(out.back(), "predict_ms"))) << out.back();
  const double x_now = field(out.back(), "x_m");
  const double vx_now = field(out.back(), "vx_mps");
  r = run("locate --predict-ms 100 --replay " + rec.string());  // implies --filter
  ASSERT_EQ(r.exit_code, 0) << r.err;
  out = lines(r.out);
  ASSERT_EQ(out.size(), poses.size());
  EXPECT_EQ(field(out.back(), "predict_ms"), 100.0) << out.back();
  // Constant acceleration: 100 ms ahead at the mean of the two velocities.
  const double vx_ahead = field(out.back(), "vx_mps");
  EXPECT_NEAR(field(out.back(), "x_m") - x_now, 0.1 * 0.5 * (vx_now + vx_ahead), 1e-4)
      << out.back();
  // Against the truth the prediction carries the filter's acceleration,
  // estimated from 0.1 mm of frame noise at 30 Hz: measured 0.36 m/s², so
  // 2.7 mm and 0.045 m/s off 100 ms ahead (2026-12-04).
  EXPECT_NEAR(field(out.back(), "x_m") - x_now, 0.06, 0.004) << out.back();
  EXPECT_NEAR(vx_ahead, 0.6, 0.06) << out.back();
  EXPECT_EQ(run("locate --predict-ms nope --replay " + rec.string()).exit_code, 2);
}

// The horizon every client honours (filter.predict_horizon_ms, 200 ms by
// default): a prediction beyond it is a usage error naming it; NaN too.
TEST_F(LocateCommand, PredictionBeyondTheFiltersHorizonIsAUsageError) {
  const fs::path rec = record({{1.2, 1.5, 0.3}, {1.22, 1.5, 0.3}});
  for (const char* ms : {"250", "-201"}) {
    const CommandRun r =
        run(std::string("locate --predict-ms ") + ms + " --replay " + rec.string());
    EXPECT_EQ(r.exit_code, 2) << ms << ": " << r.err;
    EXPECT_NE(r.err.find("beyond the filter's horizon of 200 ms (filter.predict_horizon_ms"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(r.out, "") << ms;
  }
  const CommandRun nan = run("locate --predict-ms nan --replay " + rec.string());
  EXPECT_EQ(nan.exit_code, 2) << nan.err;
  EXPECT_NE(nan.err.find("--predict-ms: must be a finite number, got 'nan'"), std::string::npos)
      << nan.err;
}

TEST_F(LocateCommand, MalformedRecordingExitsFourNamingFileAndLine) {
  const fs::path rec = record({{1.2, 1.5, 0.3}, {2.0, 2.2, -2.0}});
  {
    std::ofstream csv(rec / "frames.csv", std::ios::app);
    csv << "2,banana,frames/000002.png,1,1,0\n";
  }
  const CommandRun r = run("locate --replay " + rec.string());
  EXPECT_EQ(r.exit_code, 4);
  EXPECT_NE(r.err.find("frames.csv:4:"), std::string::npos) << "file and line 4 named: " << r.err;
  EXPECT_NE(r.err.find("banana"), std::string::npos) << "the bad value named: " << r.err;
  EXPECT_TRUE(r.out.empty());
}

TEST_F(LocateCommand, MissingRecordingExitsFour) {
  const CommandRun r = run("locate --replay " + (dir_ / "nothing").string());
  EXPECT_EQ(r.exit_code, 4);
  EXPECT_NE(r.err.find("nothing"), std::string::npos) << r.err;
}

TEST_F(LocateCommand, UnknownModeIsAUsageError) {
  const CommandRun r = run("locate --mode fancy --replay " + dir_.string());
  EXPECT_EQ(r.exit_code, 2);
}

TEST_F(LocateCommand, MissingReplayIsAUsageError) {
  const CommandRun r = run("locate");
  EXPECT_EQ(r.exit_code, 2);
}

TEST_F(LocateCommand, UnreadableConfigExitsFourNamingTheFile) {
  const fs::path rec = record({{1.2, 1.5, 0.3}});
  const CommandRun r =
      run("locate --config " + (dir_ / "absent.yaml").string() + " --replay " + rec.string());
  EXPECT_EQ(r.exit_code, 4);
  EXPECT_NE(r.err.find("absent.yaml"), std::string::npos) << r.err;
}

TEST_F(LocateCommand, ConfigFileOverridesDefaults) {
  const fs::path rec = record({{1.2, 1.5, 0.3}});
  // A mount offset moves the reported robot pose by that offset.
  {
    std::ofstream yaml(dir_ / "c.yaml");
    yaml << "mount:\n  offset_forward_m: 0.1\n";
  }
  const CommandRun r =
      run("locate --config " + (dir_ / "c.yaml").string() + " --replay " + rec.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto out = lines(r.out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(field(out[0], "x_m"), 1.2 - 0.1 * std::cos(0.3), 0.005) << out[0];
  EXPECT_NEAR(field(out[0], "y_m"), 1.5 - 0.1 * std::sin(0.3), 0.005) << out[0];
}

TEST_F(LocateCommand, HeightsThatDisagreeWithTheMarkersGiveNoPoseAndSaySo) {
  // Ceiling 3.0 m, lens 0.5 m: the markers are 2.5 m away, SPEC's defaults
  // say 2.134 m. Solved with the defaults, such views gave poses up to
  // 0.74 m off under the residual limit; they must be refused, with a word why.
  const std::vector<Pose2D> poses{{1.2, 1.5, 0.3}, {2.0, 2.2, -2.0}, {3.0, 1.0, 1.6}};
  const fs::path rec = record(poses, 3.0, 0.5);
  CommandRun r = run("locate --replay " + rec.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto out = lines(r.out);
  ASSERT_EQ(out.size(), poses.size());
  for (const auto& l : out) {
    EXPECT_NE(l.find("\"valid\":false"), std::string::npos) << l;
    EXPECT_NE(l.find("\"refusal\":\"wrong_heights\""), std::string::npos) << l;
  }
  for (const char* word :
       {"warning", "2.500 m", "2.134 m", "ceiling.height_m", "mount.lens_height_m", "--config"}) {
    EXPECT_NE(r.err.find(word), std::string::npos) << word << " in: " << r.err;
  }

  {
    std::ofstream yaml(dir_ / "heights.yaml");
    yaml << "ceiling:\n  height_m: 3.0\nmount:\n  lens_height_m: 0.5\n";
  }
  r = run("locate --config " + (dir_ / "heights.yaml").string() + " --replay " + rec.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  out = lines(r.out);
  ASSERT_EQ(out.size(), poses.size());
  for (size_t k = 0; k < poses.size(); ++k) {
    EXPECT_NEAR(field(out[k], "x_m"), poses[k].x_m, 0.005) << out[k];
    EXPECT_NEAR(field(out[k], "y_m"), poses[k].y_m, 0.005) << out[k];
  }
  EXPECT_TRUE(r.err.empty()) << r.err;
}

TEST_F(LocateCommand, MapMovesThePosesWithTheMarkersAndLeavesUnlistedMarkersUnused) {
  const std::vector<Pose2D> poses{{1.2, 1.5, 0.3}, {2.0, 2.2, -2.0}};
  const fs::path rec = record(poses);
  // Every marker 4 mm further East than nominal (inside the datum's 5 mm
  // tolerance, calibration/map_file.cpp): the poses follow them.
  std::string shifted = "format: ceilpose-map\nversion: 1\nmarkers:\n";
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i)
      shifted += "  - code: [" + std::to_string(i) + ", " + std::to_string(j) +
                 "]\n    x_m: " + std::to_string(i * 0.6096 + 0.004) +
                 "\n    y_m: " + std::to_string(j * 0.6096) + "\n    sigma_m: 0.0005\n";
  const fs::path map = dir_ / "map.yaml";
  std::ofstream(map) << shifted;
  const CommandRun r = run("locate --replay " + rec.string() + " --map " + map.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto out = lines(r.out);
  ASSERT_EQ(out.size(), 2u);
  for (size_t k = 0; k < poses.size(); ++k) {
    EXPECT_NEAR(field(out[k], "x_m"), poses[k].x_m + 0.004, 0.001) << out[k];
    EXPECT_NEAR(field(out[k], "y_m"), poses[k].y_m, 0.001) << out[k];
    // The map's sigmas are in the covariance: 0.5 mm per marker over ~9
    // markers is ~0.17 mm (the pixel noise alone gives ~0.05 mm).
    const size_t cov = out[k].find("\"cov\":[");
    ASSERT_NE(cov, std::string::npos) << out[k];
    EXPECT_GE(std::strtod(out[k].c_str() + cov + 7, nullptr), 1.5e-8) << out[k];
  }
  // A map that lists a marker far from these poses only: nothing is used.
  const fs::path far = dir_ / "far.yaml";
  std::ofstream(far) << "format: ceilpose-map\nversion: 1\nmarkers:\n  - code: [7, 7]\n"
                        "    x_m: 4.2672\n    y_m: 4.2672\n";
  const CommandRun unmapped = run("locate --replay " + rec.string() + " --map " + far.string());
  ASSERT_EQ(unmapped.exit_code, 0) << unmapped.err;
  for (const std::string& l : lines(unmapped.out))
    EXPECT_NE(l.find("\"valid\":false,\"x_m\":null"), std::string::npos) << l;
  for (const std::string& l : lines(unmapped.out))
    EXPECT_NE(l.find("\"refusal\":\"unmapped_markers\""), std::string::npos) << l;
}

TEST_F(LocateCommand, BadMapOrCameraFileExitsFourNamingTheFile) {
  const fs::path rec = record({{1.2, 1.5, 0.3}});
  const fs::path map = dir_ / "twice.yaml";
  std::ofstream(map) << "format: ceilpose-map\nversion: 1\nmarkers:\n"
                        "  - code: [1, 1]\n    x_m: 0.6\n    y_m: 0.6\n"
                        "  - code: [1, 1]\n    x_m: 0.6\n    y_m: 0.6\n";
  const CommandRun r = run("locate --replay " + rec.string() + " --map " + map.string());
  EXPECT_EQ(r.exit_code, 4);
  EXPECT_NE(r.err.find(map.string() + ":7: markers[1] (code [1, 1]): code listed twice"),
            std::string::npos)
      << r.err;
  const fs::path camera = dir_ / "camera.yaml";
  std::ofstream(camera) << "image_width: 320\nimage_height: 240\ncamera_matrix: {rows: 3, cols: "
                           "3, data: [265, 0, 159.5, 0, 265, 119.5, 0, 0, 1]}\n"
                           "distortion_coefficients: {rows: 1, cols: 5, data: [0, 0, 0, 0, 0]}\n";
  const CommandRun c = run("evaluate --replay " + rec.string() + " --camera " + camera.string());
  EXPECT_EQ(c.exit_code, 4);
  EXPECT_NE(c.err.find(camera.string() + ": calibrated for 320x240 px but the recording"),
            std::string::npos)
      << c.err;
}

TEST_F(LocateCommand, AnnotateWritesOnePictureOfWhatTheDetectorSawPerFrame) {
  const std::vector<Pose2D> poses{{1.2, 1.5, 0.3}, {-20.0, -20.0, 0.0}, {2.0, 2.2, -2.0}};
  const fs::path rec = record(poses);
  const fs::path all = dir_ / "all", refused = dir_ / "refused";
  const CommandRun r = run("locate --replay " + rec.string() + " --annotate " + all.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("wrote 3 annotated frames"), std::string::npos) << r.err;
  for (const char* name : {"frame_000000.png", "frame_000001.png", "frame_000002.png"}) {
    const fs::path png = all / name;
    ASSERT_TRUE(fs::exists(png)) << png;
    std::ifstream in(png, std::ios::binary);
    char magic[8] = {};
    in.read(magic, 8);
    EXPECT_EQ(std::string(magic + 1, 3), "PNG") << png;
  }
  const CommandRun only = run("locate --replay " + rec.string() + " --annotate " +
                              refused.string() + " --annotate-refused");
  ASSERT_EQ(only.exit_code, 0) << only.err;
  EXPECT_TRUE(fs::exists(refused / "frame_000001.png"));
  EXPECT_FALSE(fs::exists(refused / "frame_000000.png")) << "a frame with a pose was annotated";
  // The JSON Lines are the same with or without pictures.
  EXPECT_EQ(lines(only.out).size(), 3u);
}

// Issue 28, defect 11: a symbolic link planted in the picture directory
// made `locate --annotate` write wherever it pointed.
TEST_F(LocateCommand, AnnotateDoesNotFollowALinkPlantedInItsDirectory) {
  const fs::path rec = record({{1.2, 1.5, 0.3}});
  const fs::path pictures = dir_ / "pictures", victim = dir_ / "victim.txt";
  fs::create_directories(pictures);
  std::ofstream(victim) << "precious\n";
  fs::create_symlink(victim, pictures / "frame_000000.png");
  const CommandRun r = run("locate --replay " + rec.string() + " --annotate " + pictures.string());
  EXPECT_NE(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("frame_000000.png: is a symbolic link: not followed"), std::string::npos)
      << r.err;
  std::ifstream in(victim);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "precious\n");
}

// Issue 28, defect 14: 32-Mpx frames under a memory limit ended `locate` in
// an uncaught std::bad_alloc (SIGABRT) on a decoding thread, or, at a lower
// limit, were called "corrupt PNG data". Decoding now takes at most
// FramePrefetcher::kDecodeBudgetBytes whatever --decode-threads says, and
// running out of memory is named as such. At the limits where decoding runs
// out, OpenCV's first decode used to register GDAL's drivers, which abort()
// on a failed allocation (SIGABRT, SIGSEGV in 2 of 3 runs at 800 MiB).
TEST_F(LocateCommand, ThirtyTwoMegapixelFramesUnderAMemoryLimitNameTheCause) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  GTEST_SKIP() << "sanitizers reserve terabytes of address space: no ulimit -v can be set";
#endif
  const fs::path rec = dir_ / "big";
  CameraIntrinsics k = sim::SceneOptions{}.intrinsics;
  k.width = 6000;
  k.height = 5400;
  k.cx = 2999.5;
  k.cy = 2699.5;
  auto writer = RecordingWriter::create(rec.string(), RecordingCamera{k, "32 Mpx"});
  ASSERT_TRUE(writer.ok()) << writer.error().message;
  Image image;
  image.resize(k.width, k.height, PixelFormat::kRgb24);
  for (int f = 0; f < 3; ++f)
    ASSERT_TRUE(writer->append(image.view(), 1'000'000'000 + 33'333'333 * int64_t(f), nullptr));
  ASSERT_TRUE(writer->close().ok());

  const CommandRun many = run("locate --replay " + rec.string() + " --decode-threads 16");
  EXPECT_EQ(many.exit_code, 0) << many.err;
  EXPECT_NE(many.err.find("decoding on 4 threads, not 16: 6000x5400 frames on more would hold "
                          "over 1024 MiB"),
            std::string::npos)
      << many.err;
  EXPECT_EQ(lines(many.out).size(), 3u);

  bool named = false;
  for (int limit_mib : {400, 600, 700, 750, 800, 850, 900, 1000, 1200}) {
    const CommandRun r = run("locate --replay " + rec.string() + " --decode-threads 16",
                             "ulimit -v " + std::to_string(limit_mib * 1024) + "; ");
    SCOPED_TRACE("ulimit -v " + std::to_string(limit_mib) + " MiB");
    ASSERT_NE(r.exit_code, -1) << "ended by a signal: " << r.err;
    EXPECT_EQ(r.err.find("corrupt"), std::string::npos) << r.err;

    if (r.exit_code == 0) continue;
    EXPECT_TRUE(r.exit_code == kExitBadInput || r.exit_code == kExitFailure) << r.err;
    EXPECT_NE(r.err.find("memory"), std::string::npos) << r.err;
    named = named ||
            r.err.find("not enough memory to decode this 6000x5400 frame") != std::string::npos;
  }
  EXPECT_TRUE(named) << "no limit tried failed in decoding";
}

TEST_F(LocateCommand, EvaluateScoresAgainstGroundTruth) {
  const fs::path rec = record({{1.2, 1.5, 0.3}, {2.0, 2.2, -2.0}, {-20.0, -20.0, 0.0}});
  const CommandRun r = run("evaluate --json --replay " + rec.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(field(r.out, "frames"), 3.0) << r.out;
  EXPECT_EQ(field(r.out, "frames_with_whole"), 2.0) << r.out;
  EXPECT_EQ(field(r.out, "availability"), 1.0) << r.out;
  EXPECT_EQ(field(r.out, "within_both"), 1.0) << r.out;
  EXPECT_EQ(field(r.out, "gross"), 0.0) << r.out;
  EXPECT_LT(field(r.out, "max_error_mm"), 5.0) << r.out;
  EXPECT_EQ(r.out.find("\"motion\""), std::string::npos) << "motion only with the filter";
}

TEST_F(LocateCommand, EvaluateWithTheFilterScoresVelocityAndPrediction) {
  std::vector<Pose2D> poses;
  for (int k = 0; k < 30; ++k) poses.push_back({1.0 + 0.02 * k, 1.5, 0.0});  // 0.6 m/s East
  const CommandRun r = run("evaluate --json --predict-ms 66.666 --replay " + rec_of(poses));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string motion = r.out.substr(r.out.find("\"motion\""));
  EXPECT_EQ(field(motion, "frames"), 30.0) << r.out;
  EXPECT_EQ(field(motion, "velocity_frames"), 28.0) << r.out;
  EXPECT_LT(field(motion, "velocity_median_error_mps"), 0.01) << r.out;
  EXPECT_EQ(field(motion, "predicted_frames"), 28.0) << r.out;  // the last two have no truth ahead
  EXPECT_LT(field(motion, "predicted_median_error_mm"), 1.0) << r.out;
  EXPECT_NEAR(field(motion, "unpredicted_p99_error_mm"), 40.0, 2.0) << r.out;
}

}  // namespace
}  // namespace ceilpose
