// `ceilposectl calibrate camera` and `calibrate mount` on simulated
// recordings with known truth, through the built binary: the camera against
// the true one pixel by pixel, the mount within SPEC §10's needs, and the
// refusals that say what is missing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "calibration/camera_info_file.h"
#include "config/service_config.h"
#include "tests/ctl/run_ceilposectl.h"

namespace ceilpose::test {
namespace {

namespace fs = std::filesystem;

// Rendering and localizing a few hundred frames takes minutes under ASan.
constexpr int kSlowMs = 900'000;

class Calibrate : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("ceilpose-calibrate-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name)) << text;
    return path(name);
  }
  fs::path dir_;
};

// A camera with strong barrel distortion and an off-centre principal point.
const char* kTrueCamera =
    "image_width: 640\nimage_height: 480\ncamera_matrix: {rows: 3, cols: 3, data: [536.0, 0.0, "
    "322.3, 0.0, 534.5, 236.8, 0.0, 0.0, 1.0]}\ndistortion_model: plumb_bob\n"
    "distortion_coefficients: {rows: 1, cols: 5, data: [-0.30, 0.12, 0.0012, -0.0008, -0.02]}\n";

// Largest distance between where the true camera and the estimate put the
// same ray, over a fine grid of rays that the true camera sees inside the
// image (forward projections only: exact for any distortion).
double max_pixel_difference(const CameraIntrinsics& truth, const CameraIntrinsics& estimate,
                            double margin_px = 0.0) {
  double worst = 0.0;
  for (double y = -0.8; y <= 0.8; y += 0.01)
    for (double x = -1.0; x <= 1.0; x += 0.01) {
      double ut = 0.0, vt = 0.0, ue = 0.0, ve = 0.0;
      project_camera_point(truth, {x, y, 1.0}, &ut, &vt);
      if (ut < margin_px || vt < margin_px || ut > truth.width - 1 - margin_px ||
          vt > truth.height - 1 - margin_px)
        continue;
      project_camera_point(estimate, {x, y, 1.0}, &ue, &ve);
      worst = std::max(worst, std::hypot(ue - ut, ve - vt));
    }
  return worst;
}

TEST_F(Calibrate, CameraFromACheckerboardMatchesTheTrueCameraOverTheImage) {
  const std::string truth = write("true.yaml", kTrueCamera);
  auto rendered = run_ceilposectl({"render", "--scenario", "checkerboard", "--frames", "30",
                                   "--seed", "4", "--true-camera", truth, "--out", path("board")},
                                  kSlowMs);
  ASSERT_EQ(rendered.exit_code, 0) << rendered.err;
  auto r = run_ceilposectl({"calibrate", "camera", "--replay", path("board"), "--board",
                            "checkerboard:9x6:0.03", "--out", path("camera.yaml")},
                           kSlowMs);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("30 views, RMS reprojection error 0.0"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("view  29 (frame 29):"), std::string::npos) << r.err;
  auto estimate = read_camera_info_file(path("camera.yaml"));
  ASSERT_TRUE(estimate) << estimate.error().message;
  auto expected = read_camera_info_file(truth);
  ASSERT_TRUE(expected);
  // Measured (30 views, k1 -0.30): 2.2 px at worst in the image corners the
  // boards never reach, 1.3 px 40 px in from the border (cx 0.8 px off).
  EXPECT_LT(max_pixel_difference(*expected, *estimate), 3.0);
  EXPECT_LT(max_pixel_difference(*expected, *estimate, 40.0), 1.8);
  EXPECT_NEAR(estimate->fx, 536.0, 1.5);
  EXPECT_NEAR(estimate->distortion[0], -0.30, 0.01);
}

TEST_F(Calibrate, CameraWithTooFewViewsIsRefusedSayingSo) {
  auto rendered = run_ceilposectl(
      {"render", "--scenario", "checkerboard", "--frames", "6", "--out", path("few")}, kSlowMs);
  ASSERT_EQ(rendered.exit_code, 0) << rendered.err;
  auto r = run_ceilposectl({"calibrate", "camera", "--replay", path("few"), "--board",
                            "checkerboard:9x6:0.03", "--out", path("camera.yaml")},
                           kSlowMs);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("found in 6 of 6 frames; at least 10 views are needed"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("camera.yaml")));
  auto usage = run_ceilposectl(
      {"calibrate", "camera", "--replay", path("few"), "--board", "chessboard:9x6"}, kSlowMs);
  EXPECT_EQ(usage.exit_code, 2) << usage.err;
}

// Debian's opencv-doc package: OpenCV's own real checkerboard photographs
// (640x480 greyscale JPEG, 9x6 inner corners), installed by scripts/setup.
const char* kOpenCvPhotos = "/usr/share/doc/opencv-doc/examples/data";
const char* kPhotoNames[] = {"left01", "left02", "left03", "left04", "left05", "left06", "left07",
                             "left08", "left09", "left11", "left12", "left13", "left14"};

// A recording (SPEC §4) of the given frame files, copied in order.
void write_photo_recording(const fs::path& dir, const std::vector<std::string>& files) {
  fs::create_directories(dir / "frames");
  std::ofstream csv(dir / "frames.csv");
  csv << "index,timestamp_ns,file\n";
  for (size_t i = 0; i < files.size(); ++i) {
    const std::string name = "frames/" + std::to_string(100000 + i).substr(1) + ".jpg";
    fs::copy_file(files[i], dir / name);
    csv << i << "," << 1'000'000'000 + 100'000'000 * static_cast<long long>(i) << "," << name
        << "\n";
  }
  std::ofstream(dir / "recording.yaml")
      << "format: ceilpose-recording\nversion: 1\ncamera:\n  width: 640\n  height: 480\n"
         "  fx: 530.0\n  fy: 530.0\n  cx: 319.5\n  cy: 239.5\n"
         "  distortion: [0.0, 0.0, 0.0, 0.0, 0.0]\n";
}

double number_after(const std::string& text, const std::string& key) {
  const size_t at = text.find(key);
  return at == std::string::npos ? NAN : std::stod(text.substr(at + key.size()));
}

TEST_F(Calibrate, CameraFromRealGreyscalePhotographsGeneralisesAsWellAsOpenCv) {
  std::vector<std::string> files;
  for (const char* name : kPhotoNames)
    files.push_back(std::string(kOpenCvPhotos) + "/" + name + ".jpg");
  ASSERT_TRUE(fs::exists(files.front())) << files.front() << ": run scripts/setup (opencv-doc)";
  write_photo_recording(dir_ / "photos", files);
  auto r = run_ceilposectl({"calibrate", "camera", "--replay", path("photos"), "--board",
                            "checkerboard:9x6:0.025", "--out", path("camera.yaml")},
                           kSlowMs);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double ours = number_after(r.err, "the views reproject at ");
  // OpenCV's calibrateCamera, left-one-out, as a user would run it.
  std::vector<std::vector<cv::Point2f>> corners;
  for (const std::string& f : files) {
    const cv::Mat gray = cv::imread(f, cv::IMREAD_GRAYSCALE);
    std::vector<cv::Point2f> c;
    ASSERT_TRUE(cv::findChessboardCorners(gray, cv::Size(9, 6), c)) << f;
    cv::cornerSubPix(gray, c, cv::Size(5, 5), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4));
    corners.push_back(c);
  }
  std::vector<cv::Point3f> model;
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 9; ++x) model.emplace_back(0.025f * x, 0.025f * y, 0.0f);
  double sum_sq = 0.0;
  for (size_t out = 0; out < corners.size(); ++out) {
    std::vector<std::vector<cv::Point3f>> object;
    std::vector<std::vector<cv::Point2f>> image;
    for (size_t v = 0; v < corners.size(); ++v)
      if (v != out) {
        object.push_back(model);
        image.push_back(corners[v]);
      }
    cv::Mat k, dist, rvec, tvec;
    std::vector<cv::Mat> rvecs, tvecs;
    cv::calibrateCamera(object, image, cv::Size(640, 480), k, dist, rvecs, tvecs);
    cv::solvePnP(model, corners[out], k, dist, rvec, tvec);
    std::vector<cv::Point2f> projected;
    cv::projectPoints(model, rvec, tvec, k, dist, projected);
    for (size_t c = 0; c < model.size(); ++c)
      sum_sq += std::pow(cv::norm(projected[c] - corners[out][c]), 2) / model.size();
  }
  const double opencv = std::sqrt(sum_sq / corners.size());
  std::printf("held out of the fit: ceilpose %.3f px RMS, OpenCV calibrateCamera %.3f px\n", ours,
              opencv);
  // Measured: 0.201 px both (13 photographs).
  EXPECT_LE(ours, opencv + 1e-3) << r.err;
  EXPECT_LT(ours, 0.25) << r.err;
  auto camera = read_camera_info_file(path("camera.yaml"));
  ASSERT_TRUE(camera) << camera.error().message;
  EXPECT_NEAR(camera->fx, 533.0, 3.0);
  EXPECT_NEAR(camera->cx, 342.5, 3.0);
}

TEST_F(Calibrate, CameraFromTwelveIdenticalViewsIsRefusedAndTheOldFileIsKept) {
  const std::string photo = std::string(kOpenCvPhotos) + "/left01.jpg";
  ASSERT_TRUE(fs::exists(photo)) << photo << ": run scripts/setup (opencv-doc)";
  write_photo_recording(dir_ / "same", std::vector<std::string>(12, photo));
  const std::string old = write("camera.yaml", "an older calibration\n");
  auto r = run_ceilposectl({"calibrate", "camera", "--replay", path("same"), "--board",
                            "checkerboard:9x6:0.025", "--out", old},
                           kSlowMs);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("11 of them repeating another view"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1 distinct"), std::string::npos) << r.err;
  std::ifstream in(old);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "an older calibration\n");
}

// Issue 28, defect 25: a wrong --board ran 45 s without a word.
TEST_F(Calibrate, CameraWithTheWrongBoardStopsEarlySayingWhy) {
  const std::string photo = std::string(kOpenCvPhotos) + "/left01.jpg";
  ASSERT_TRUE(fs::exists(photo)) << photo << ": run scripts/setup (opencv-doc)";
  write_photo_recording(dir_ / "rec", std::vector<std::string>(14, photo));
  auto r = run_ceilposectl({"calibrate", "camera", "--replay", path("rec"), "--board",
                            "checkerboard:7x5:0.025", "--out", path("camera.yaml")},
                           kSlowMs);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("calibrate camera: frame 10/14, board in 0"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("the 7x5 board was not found in the first 10 frames; stopped. Is --board "
                       "right?"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("camera.yaml")));
}

TEST_F(Calibrate, NoCalibrationWritesOverItsOwnInput) {
  const std::string photo = std::string(kOpenCvPhotos) + "/left01.jpg";
  ASSERT_TRUE(fs::exists(photo)) << photo << ": run scripts/setup (opencv-doc)";
  write_photo_recording(dir_ / "rec", {photo});
  const std::string yaml = path("rec/recording.yaml");
  auto camera = run_ceilposectl({"calibrate", "camera", "--replay", path("rec"), "--board",
                                 "checkerboard:9x6:0.025", "--out", yaml},
                                kSlowMs);
  EXPECT_EQ(camera.exit_code, 2) << camera.err;
  EXPECT_NE(camera.err.find("is inside --replay"), std::string::npos) << camera.err;
  const std::string config = write("robot.yaml", "mount:\n  lens_height_m: 0.3048\n");
  auto mount = run_ceilposectl(
      {"calibrate", "mount", "--replay", path("rec"), "--config", config, "--out", config},
      kSlowMs);
  EXPECT_EQ(mount.exit_code, 2) << mount.err;
  EXPECT_NE(mount.err.find("--out " + config + " is --config's file"), std::string::npos)
      << mount.err;
  auto survey = run_ceilposectl({"survey", "--replay", path("rec"), "--intrinsics", "--out",
                                 path("x.yaml"), "--camera-out", path("x.yaml")},
                                kSlowMs);
  EXPECT_EQ(survey.exit_code, 2) << survey.err;
  EXPECT_NE(survey.err.find("are both"), std::string::npos) << survey.err;
  auto robot =
      run_ceilposectl({"calibrate", "robot", "--replay", path("rec"), "--map", path("map.yaml"),
                       "--config", config, "--camera-out", path("c.yaml"), "--mount-out", config},
                      kSlowMs);
  EXPECT_EQ(robot.exit_code, 2) << robot.err;
  EXPECT_NE(robot.err.find("--mount-out " + config + " is --config's file"), std::string::npos)
      << robot.err;
  std::ifstream in(config);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}),
            "mount:\n  lens_height_m: 0.3048\n");
  EXPECT_TRUE(fs::exists(yaml));
}

// render --truth-map is written first: over --config it replaced the
// configuration the frames were to be rendered with, and inside --out it
// made the recording's directory non-empty before the recording began.
TEST_F(Calibrate, RenderWritesItsTruthMapOverNoInputAndNotIntoItsRecording) {
  const std::string config = write("robot.yaml", "mount:\n  lens_height_m: 0.3048\n");
  auto over = run_ceilposectl({"render", "--scenario", "random", "--frames", "2", "--config",
                               config, "--truth-map", config, "--out", path("r1")},
                              kSlowMs);
  EXPECT_EQ(over.exit_code, 2) << over.err;
  EXPECT_NE(over.err.find("--truth-map " + config + " is --config's file"), std::string::npos)
      << over.err;
  std::ifstream in(config);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}),
            "mount:\n  lens_height_m: 0.3048\n");
  EXPECT_FALSE(fs::exists(path("r1")));
  auto inside = run_ceilposectl({"render", "--scenario", "random", "--frames", "2", "--truth-map",
                                 path("r2/map.yaml"), "--out", path("r2")},
                                kSlowMs);
  EXPECT_EQ(inside.exit_code, 2) << inside.err;
  EXPECT_NE(inside.err.find("is inside --out"), std::string::npos) << inside.err;
  EXPECT_FALSE(fs::exists(path("r2")));
}

// issue 27's robot: a camera 17 px off-centre (12, 12), non-square pixels
// and k1 -0.22, mounted 85 mm behind and 30 mm left of the origin, turned
// -3°, under a hand-laid ceiling whose true map is known.
const char* kRobotCamera =
    "image_width: 640\nimage_height: 480\ncamera_matrix: {rows: 3, cols: 3, data: [528.0, 0.0, "
    "331.5, 0.0, 536.0, 251.5, 0.0, 0.0, 1.0]}\ndistortion_model: plumb_bob\n"
    "distortion_coefficients: {rows: 1, cols: 5, data: [-0.22, 0.05, 0.0, 0.0, 0.0]}\n";
const char* kRobotMount =
    "mount:\n  offset_forward_m: -0.085\n  offset_left_m: 0.030\n  yaw_rad: -0.0523599\n";

class CalibrateRobot : public Calibrate {
 protected:
  // Renders `scenario` through the robot's camera and mount under the
  // hand-laid ceiling of seed 5 (its true map in truth_map.yaml).
  void render(const std::string& scenario, int frames, int seed, const std::string& out) {
    auto r = run_ceilposectl(
        {"render", "--scenario", scenario, "--frames", std::to_string(frames), "--seed",
         std::to_string(seed), "--config", write("mount_truth.yaml", kRobotMount), "--true-camera",
         write("true_camera.yaml", kRobotCamera), "--ceiling", "hand-laid", "--ceiling-seed", "5",
         "--truth-map", path("truth_map.yaml"), "--out", path(out)},
        kSlowMs);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
};

TEST_F(CalibrateRobot, OneDriveGivesACameraAndMountThatLocalizeWithinAMillimetre) {
  render("robot_drive", 300, 5, "drive");
  auto r = run_ceilposectl(
      {"calibrate", "robot", "--replay", path("drive"), "--map", path("truth_map.yaml"),
       "--camera-out", path("camera.yaml"), "--mount-out", path("mount.yaml")},
      kSlowMs);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("determined by the drive (1-sigma)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not determined by the drive"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("lens height"), std::string::npos) << r.err;
  auto camera = read_camera_info_file(path("camera.yaml"));
  ASSERT_TRUE(camera) << camera.error().message;
  // Measured: fx 528.00, fy 535.99, k1 -0.2201, cx 331.53, cy 251.51.
  EXPECT_NEAR(camera->fx, 528.0, 0.5);
  EXPECT_NEAR(camera->fy, 536.0, 0.5);
  EXPECT_NEAR(camera->distortion[0], -0.22, 0.005);
  auto mount = load_config_file(path("mount.yaml"));
  ASSERT_TRUE(mount) << mount.error().message;
  // Measured: -85.0 mm, 30.1 mm, -2.996°; the principal point found, the
  // offset is the true one.
  EXPECT_NEAR(mount->pipeline.mount.offset_forward_m, -0.085, 0.002);
  EXPECT_NEAR(mount->pipeline.mount.offset_left_m, 0.030, 0.002);
  EXPECT_NEAR(mount->pipeline.mount.yaw_rad, -0.0523599, 0.1 * std::numbers::pi / 180);
  // Other frames of the same robot, localized with both files.
  render("nominal", 100, 9, "other");
  auto located =
      run_ceilposectl({"evaluate", "--replay", path("other"), "--map", path("truth_map.yaml"),
                       "--camera", path("camera.yaml"), "--config", path("mount.yaml"), "--json"},
                      kSlowMs);
  ASSERT_EQ(located.exit_code, 0) << located.err;
  // Measured: median 0.06 mm, p99 0.17 mm (issue 27's goal: 1 mm, 3 mm).
  EXPECT_LT(number_after(located.out, "\"median_error_mm\":"), 0.3) << located.out;
  EXPECT_LT(number_after(located.out, "\"p99_error_mm\":"), 0.8) << located.out;
  EXPECT_EQ(number_after(located.out, "\"gross\":"), 0) << located.out;
}

TEST_F(CalibrateRobot, ADriveWithoutATurnInPlaceIsRefusedAndWritesNothing) {
  render("drive", 120, 5, "drive");
  const std::string old = write("mount.yaml", "mount:\n  offset_forward_m: 0.1\n");
  auto r = run_ceilposectl(
      {"calibrate", "robot", "--replay", path("drive"), "--map", path("truth_map.yaml"),
       "--camera-out", path("camera.yaml"), "--mount-out", old},
      kSlowMs);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("lacks turning in place"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nothing was written"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("camera.yaml")));
  std::ifstream in(old);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}),
            "mount:\n  offset_forward_m: 0.1\n");
}

TEST_F(CalibrateRobot, SurveyIntrinsicsSaysTheOriginIsOpenAndRefusesAMountItCannotFind) {
  render("drive", 120, 5, "drive");
  auto r = run_ceilposectl(
      {"survey", "--replay", path("drive"), "--camera", path("true_camera.yaml"), "--intrinsics",
       "--camera-out", path("camera.yaml"), "--out", path("map.yaml")},
      kSlowMs);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("cx 331.50 cy 251.50 px, p1 0.000000 p2 0.000000 k3 0.00000 held"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("the robot's origin is undetermined until `calibrate robot`"),
            std::string::npos)
      << r.err;
  std::ifstream camera(path("camera.yaml"));
  const std::string text(std::istreambuf_iterator<char>(camera), {});
  EXPECT_EQ(text.rfind("# ceilposectl survey --intrinsics: fx, fy, k1, k2 estimated", 0), 0u)
      << text;
  EXPECT_TRUE(read_camera_info_file(path("camera.yaml")));
  // The curving drive has no turn in place: no mount, and then nothing.
  auto m =
      run_ceilposectl({"survey", "--replay", path("drive"), "--camera", path("true_camera.yaml"),
                       "--out", path("map2.yaml"), "--mount-out", path("mount.yaml")},
                      kSlowMs);
  EXPECT_EQ(m.exit_code, 1) << m.err;
  EXPECT_NE(m.err.find("--mount-out: the recording lacks turning in place"), std::string::npos)
      << m.err;
  EXPECT_FALSE(fs::exists(path("map2.yaml")));
  EXPECT_FALSE(fs::exists(path("mount.yaml")));
}

TEST_F(CalibrateRobot, GreyscaleFramesAreRefusedSayingTheyHaveNoColour) {
  const std::string photo = std::string(kOpenCvPhotos) + "/left01.jpg";
  ASSERT_TRUE(fs::exists(photo)) << photo << ": run scripts/setup (opencv-doc)";
  write_photo_recording(dir_ / "grey", std::vector<std::string>(3, photo));
  auto located = run_ceilposectl({"locate", "--replay", path("grey")}, kSlowMs);
  EXPECT_EQ(located.exit_code, 0) << located.err;
  EXPECT_NE(located.out.find("\"refusal\":\"no_colour\""), std::string::npos) << located.out;
  EXPECT_NE(located.err.find("3 of 3 frames are greyscale"), std::string::npos) << located.err;
  auto mount = run_ceilposectl(
      {"calibrate", "mount", "--replay", path("grey"), "--out", path("mount.yaml")}, kSlowMs);
  EXPECT_EQ(mount.exit_code, 1) << mount.err;
  EXPECT_NE(mount.err.find("frames are greyscale"), std::string::npos) << mount.err;
  EXPECT_FALSE(fs::exists(path("mount.yaml")));
}

TEST_F(Calibrate, MountFromTurnsAndDrivesIsWithinAMillimetre) {
  // SPEC §10's case: 115 mm ahead, 42 mm right, turned 2.5°.
  const std::string truth = write("truth.yaml",
                                  "mount:\n  offset_forward_m: 0.115\n  offset_left_m: -0.042\n"
                                  "  yaw_rad: 0.0436332\n");
  auto rendered = run_ceilposectl({"render", "--scenario", "mount_drive", "--frames", "200",
                                   "--seed", "3", "--config", truth, "--out", path("drive")},
                                  kSlowMs);
  ASSERT_EQ(rendered.exit_code, 0) << rendered.err;
  auto r = run_ceilposectl(
      {"calibrate", "mount", "--replay", path("drive"), "--out", path("mount.yaml")}, kSlowMs);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto fragment = load_config_file(path("mount.yaml"));
  ASSERT_TRUE(fragment) << fragment.error().message;
  const CameraMount& m = fragment->pipeline.mount;
  // Measured (400 frames): 115.01 mm, -42.09 mm, 2.4999°; 200 frames alike.
  EXPECT_NEAR(m.offset_forward_m, 0.115, 0.0005);
  EXPECT_NEAR(m.offset_left_m, -0.042, 0.0005);
  EXPECT_NEAR(m.yaw_rad, 2.5 * std::numbers::pi / 180, 0.02 * std::numbers::pi / 180);
  EXPECT_NE(r.err.find("mm forward"), std::string::npos) << r.err;
  // Localized with it, the robot's own pose comes out.
  auto located = run_ceilposectl(
      {"evaluate", "--replay", path("drive"), "--config", path("mount.yaml"), "--json"}, kSlowMs);
  ASSERT_EQ(located.exit_code, 0) << located.err;
  const size_t at = located.out.find("\"median_error_mm\":");
  ASSERT_NE(at, std::string::npos) << located.out;
  // Measured: 0.37 mm (200 frames), 0.10 mm (400); SPEC §10's need: 1 mm.
  EXPECT_LT(std::stod(located.out.substr(at + 18)), 0.6) << located.out;
}

TEST_F(Calibrate, MountWithoutATurnOrADriveIsRefusedSayingWhich) {
  auto rendered = run_ceilposectl(
      {"render", "--scenario", "trajectory", "--frames", "40", "--out", path("patrol")}, kSlowMs);
  ASSERT_EQ(rendered.exit_code, 0) << rendered.err;
  auto r = run_ceilposectl(
      {"calibrate", "mount", "--replay", path("patrol"), "--out", path("mount.yaml")}, kSlowMs);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("the recording lacks turning in place"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("360 needed"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("mount.yaml")));
}

}  // namespace
}  // namespace ceilpose::test
