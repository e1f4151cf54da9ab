// Golden end-to-end accuracy over simulator sets: render, detect, position
// through the Localizer, and assert limits near what is measured (no looser
// than 2x the median and p99 measured on 2026-12-01 at 200 frames, and at
// 1000 frames where the tail is heavier, so that a 2x regression fails;
// docs/accuracy.md has the figures). Under sanitizers
// fewer frames run (accuracy_frames); their p99 stays below these limits.
#include <gtest/gtest.h>

#include <iostream>

#include "accuracy_support.h"
#include "pipeline/motion_metrics.h"
#include "sim/scenarios.h"

namespace ceilpose {
namespace {

constexpr uint64_t kSeed = 20240601;
constexpr double kTiltP99LimitMm = 5.2;  // the tilt set's p99 position error, least squares

void print_row(const std::string& name, const AccuracyReport& r) {
  std::cout << format_report_row(name, r) << "  (x " << 100.0 * r.within_x << "%, y "
            << 100.0 * r.within_y << "%, max " << r.max_error_mm << " mm, " << r.frames
            << " frames)\n";
}

// One set's limits; gross errors are always 0.
struct TableRow {
  const char* set;
  PositioningMode mode;
  double min_availability;
  double min_within_both;
  double max_median_mm;
  double max_p99_mm;
  double max_yaw_p99_deg;
};

void expect_row(const TableRow& row) {
  const AccuracyReport r =
      testing::run_scenario(row.set, testing::accuracy_frames(200), kSeed, row.mode);
  print_row(std::string(row.set) + " (" + std::string(to_string(row.mode)) + ")", r);
  ASSERT_GT(r.frames_with_whole, 0);
  EXPECT_GE(r.availability, row.min_availability);
  EXPECT_GE(r.within_both, row.min_within_both);
  EXPECT_LE(r.median_error_mm, row.max_median_mm);
  EXPECT_LE(r.p99_error_mm, row.max_p99_mm);
  EXPECT_LE(r.yaw_p99_deg, row.max_yaw_p99_deg);
  EXPECT_EQ(r.gross, 0);
}

// Measured at 200 frames: median / p99 position error, yaw p99.
TEST(Accuracy, NominalSetStaysNearItsMeasuredAccuracy) {
  // 0.03 / 0.11 mm, 0.005 deg (2026-12-04, edge points; 0.05 / 0.21 mm,
  // 0.008 deg before)
  expect_row({"nominal", PositioningMode::kAuto, 1.0, 1.0, 0.06, 0.22, 0.016});
}

TEST(Accuracy, StressSetStaysNearItsMeasuredAccuracy) {
  // 0.15 / 0.45 mm, 0.020 deg (2026-12-04, edge points weighed by their
  // scatter against the centroids'; weighed alike 0.20 / 0.61 mm: noise
  // sigma 6, JPEG 60 and blur move a dozen-sample edge point more than a
  // centroid of hundreds of pixels; 0.14 / 0.38 mm, 0.025 deg before edges)
  expect_row({"stress", PositioningMode::kAuto, 1.0, 1.0, 0.30, 0.90, 0.05});
}

TEST(Accuracy, TiltedCameraWithLeastSquaresStaysNearItsMeasuredAccuracy) {
  // 0.38 / 1.63 mm, 0.005 deg (2026-12-04, edge points; 0.47 / 2.57 mm
  // before them, 0.48 / 2.84 mm before the tilt decision weighed what leaving
  // the tilt out costs)
  expect_row({"tilt", PositioningMode::kLeastSquares, 1.0, 1.0, 0.94, kTiltP99LimitMm, 0.018});
}

// Issue 29 #1: every positioning set as cameras hand frames over -- YUYV
// 4:2:2 (USB cameras), NV12 and YUV420 4:2:0 (Pi cameras, ISPs), read by the
// detector with no conversion pass -- against the RGB render of the same
// frames. 4:2:0 halves the chroma vertically too, so a marker's coloured
// edge blurs over two rows: availability must hold to a frame, and the
// errors to within the noise measured between formats. The tilt set's
// errors are the free-tilt fit's own precision (sigma 1-3 mm, issue 25),
// which one format's draw of 60 frames does not measure better than
// another's: its formats are held to the set's own limit.
class AccuracyInCameraFormats : public ::testing::TestWithParam<const char*> {};

TEST_P(AccuracyInCameraFormats, StaysWithinNoiseOfRgb) {
  const int frames = testing::accuracy_frames(60);
  const AccuracyReport rgb = testing::run_scenario(GetParam(), frames, kSeed,
                                                   PositioningMode::kAuto, false, PipelineConfig{});
  print_row(std::string(GetParam()) + " RGB24", rgb);
  ASSERT_GT(rgb.frames_with_whole, 0);
  for (PixelFormat format : {PixelFormat::kYuyv, PixelFormat::kNv12, PixelFormat::kYuv420}) {
    const AccuracyReport r =
        testing::run_scenario(GetParam(), frames, kSeed, PositioningMode::kAuto, false,
                              PipelineConfig{}, nullptr, 0.0, format);
    print_row(std::string(GetParam()) + " " + to_string(format), r);
    EXPECT_EQ(r.gross, 0) << to_string(format);
    EXPECT_EQ(r.valid_without_whole, 0) << to_string(format);
    EXPECT_GE(r.valid_with_whole, rgb.valid_with_whole - 1) << to_string(format);
    EXPECT_LE(r.median_error_mm, 1.5 * rgb.median_error_mm + 0.05) << to_string(format);
    // The edges set's frames have one or two whole markers: a pose rests on
    // one marker's edge points, which the chroma a camera halves blurs (the
    // darkest channel follows it), so its worst frame differs by format by up
    // to 1 mm (20 frames: RGB 0.59, NV12 1.44 mm; 60: 1.31, 1.89 mm).
    const std::string set = GetParam();
    const double p99_limit_mm = set == "tilt"    ? kTiltP99LimitMm
                                : set == "edges" ? 1.5 * rgb.p99_error_mm + 1.0
                                                 : 1.5 * rgb.p99_error_mm + 0.2;
    EXPECT_LE(r.p99_error_mm, p99_limit_mm) << to_string(format);
  }
}

INSTANTIATE_TEST_SUITE_P(Sets, AccuracyInCameraFormats,
                         ::testing::Values("thesis_points", "random", "nominal", "trajectory",
                                           "drive", "gain", "gradient", "colour_cast", "noise",
                                           "blur", "motion_blur", "jpeg", "fixtures", "occlusion",
                                           "clutter", "stress", "tilt", "edges"));

// A recording of a YUV camera stores RGB24 (`ceilposectl record`,
// capture::to_rgb24). Converted with each pair's chroma on both its pixels
// (cv::cvtColor for YUYV, and the same for 4:2:0), every coloured edge
// snapped to a pair boundary and the replay localized worse than the camera
// had live -- the defect the detector itself had until 2026-12-04 (random
// set, YUYV: p99 11.7 mm). Replayed, a recording must localize as the
// camera's own frames did.
TEST(Accuracy, RecordingsOfYuvCamerasReplayAsTheCameraWasSeen) {
  const int frames = testing::accuracy_frames(60);
  for (const char* set : {"random", "trajectory"}) {
    for (PixelFormat format : {PixelFormat::kYuyv, PixelFormat::kNv12, PixelFormat::kYuv420}) {
      const std::string what = std::string(set) + " " + to_string(format);
      const AccuracyReport live =
          testing::run_scenario(set, frames, kSeed, PositioningMode::kAuto, false, PipelineConfig{},
                                nullptr, 0.0, format);
      const AccuracyReport replay =
          testing::run_scenario(set, frames, kSeed, PositioningMode::kAuto, false, PipelineConfig{},
                                nullptr, 0.0, format, true);
      print_row(what + " live", live);
      print_row(what + " recorded", replay);
      EXPECT_EQ(replay.gross, 0) << what;
      EXPECT_GE(replay.valid_with_whole, live.valid_with_whole - 1) << what;
      EXPECT_LE(replay.median_error_mm, 1.5 * live.median_error_mm + 0.05) << what;
      EXPECT_LE(replay.p99_error_mm, 1.5 * live.p99_error_mm + 0.2) << what;
    }
  }
}

TEST(Accuracy, FramesWithoutWholeMarkerAreInvalidAndEdgesHaveNoGrossError) {
  const AccuracyReport r =
      testing::run_scenario("edges", testing::accuracy_frames(200), kSeed, PositioningMode::kAuto);
  print_row("edges (0-2 whole markers)", r);
  ASSERT_LT(r.frames_with_whole, r.frames) << "the set must contain frames with no whole marker";
  EXPECT_EQ(r.valid_without_whole, 0);
  EXPECT_EQ(r.gross, 0);
  // Measured: availability 99.4 %, 0.12 / 5.03 mm.
  EXPECT_GE(r.availability, 0.96);
  EXPECT_LE(r.median_error_mm, 0.24);
  EXPECT_LE(r.p99_error_mm, 10.0);
}

// The daemon's filter on a patrol at 1.2 m/s with U-turns: smoothing must not
// cost accuracy or gate good measurements in the turns.
TEST(Accuracy, FilteredTrajectoryKeepsPerFrameAccuracy) {
  const AccuracyReport r = testing::run_scenario("trajectory", testing::accuracy_frames(300), kSeed,
                                                 PositioningMode::kAuto, /*filter=*/true);
  print_row("trajectory, filtered", r);
  // Measured at 300 frames: 0.24 / 0.72 mm, yaw p99 0.072 deg (constant
  // velocity); constant acceleration: 0.05 / 0.67 mm, yaw p99 0.007 deg;
  // with edge points (2026-12-04) 0.05 / 0.27 mm, 0.006 deg.
  EXPECT_EQ(r.availability, 1.0);
  EXPECT_EQ(r.within_both, 1.0);
  EXPECT_LE(r.median_error_mm, 0.10);
  EXPECT_LE(r.p99_error_mm, 0.54);
  EXPECT_LE(r.yaw_p99_deg, 0.03);
  EXPECT_EQ(r.gross, 0);
}

// A curving drive at 0.1-1.5 m/s (issue 13): the filtered pose must stay as
// close to the truth as each frame's own solution, its velocity right, and
// its prediction two frames (66.7 ms) ahead within 5 mm of where the robot
// then is.
TEST(Accuracy, FilterFollowsACurvingDriveAndPredictsIt) {
  // Half a second to settle: the filter starts at rest, and under the
  // sanitizers (90 frames) that first frame would be the p99.
  MotionAccuracySink motion(2 * sim::kScenarioFramePeriod_ns * 1e-6, 15);
  const AccuracyReport r =
      testing::run_scenario("drive", testing::accuracy_frames(450), kSeed, PositioningMode::kAuto,
                            /*filter=*/true, PipelineConfig{}, &motion);
  const MotionReport m = motion.report();
  print_row("drive, filtered", r);
  std::cout << "drive: velocity median " << m.velocity_median_error_mps << " m/s, predicted "
            << m.predict_ms << " ms p99 " << m.predicted_p99_error_mm << " mm (unpredicted "
            << m.unpredicted_p99_error_mm << " mm)\n";
  // Measured at 450 frames: 0.05 / 0.13 mm; velocity median 0.0021 m/s;
  // predicted p99 2.95 mm against 100 mm unpredicted.
  EXPECT_EQ(r.availability, 1.0);
  EXPECT_EQ(r.gross, 0);
  EXPECT_LE(m.median_error_mm, 0.1);
  EXPECT_LE(m.p99_error_mm, 0.3);
  EXPECT_LE(m.velocity_median_error_mps, 0.005);
  EXPECT_LE(m.predicted_p99_error_mm, 4.0);
  EXPECT_GE(m.unpredicted_p99_error_mm, 50.0);
}

// Issue 16: a curving drive at 0.1-1.5 m/s through rolling shutters of
// 15-35 ms, each frame solved on its own. Told the readout, lsq estimates the
// motion during it from the markers' rows and gives the centre row's pose.
AccuracyReport rolling_drive(double rendered_ms, double declared_ms, int frames) {
  PipelineConfig config;
  config.intrinsics.readout_ms = declared_ms;
  const AccuracyReport r =
      testing::run_scenario("drive", testing::accuracy_frames(frames), kSeed + 16,
                            PositioningMode::kAuto, false, config, nullptr, rendered_ms);
  print_row("drive, " + std::to_string(static_cast<int>(rendered_ms)) + " ms readout, told " +
                std::to_string(static_cast<int>(declared_ms)) + " ms",
            r);
  return r;
}

TEST(Accuracy, RollingShutterOfA25msReadoutIsModelled) {
  const AccuracyReport r = rolling_drive(25.0, 25.0, 300);
  // Measured at 300 frames: 0.06 / 0.23 mm, max 0.29 mm, yaw p99 0.011 deg;
  // not modelled (told 0 ms): 1.41 / 7.1 mm, max 8.6 mm, yaw p99 0.71 deg.
  EXPECT_EQ(r.availability, 1.0);
  EXPECT_EQ(r.gross, 0);
  EXPECT_LE(r.median_error_mm, 0.12);
  EXPECT_LE(r.p99_error_mm, 0.45);
  EXPECT_LE(r.max_error_mm, 0.6);
  EXPECT_LE(r.yaw_p99_deg, 0.03);
  const AccuracyReport unmodelled = rolling_drive(25.0, 0.0, 300);
  EXPECT_GE(unmodelled.p99_error_mm, 3.0 * r.p99_error_mm) << "the test must see a rolling shutter";
}

TEST(Accuracy, RollingShuttersOf15And35msAreModelled) {
  for (double readout_ms : {15.0, 35.0}) {
    const AccuracyReport r = rolling_drive(readout_ms, readout_ms, 150);
    EXPECT_EQ(r.gross, 0) << readout_ms;
    EXPECT_LE(r.median_error_mm, 0.15) << readout_ms;
    EXPECT_LE(r.p99_error_mm, 0.6) << readout_ms;
    EXPECT_LE(r.yaw_p99_deg, 0.04) << readout_ms;
  }
}

// Issue 16: what the frame cannot tell, the filter's motion does. With the
// filter on, each marker's answer is moved to the centre row by the filter's
// motion before the thesis modes combine them and before the markers are
// checked against each other; a pose from one row is fused at that row's
// instant (PoseEstimate::time_offset_s).
AccuracyReport filtered_rolling_drive(PositioningMode mode, double declared_ms, int frames,
                                      const PipelineConfig& base = PipelineConfig{},
                                      PoseSink* also = nullptr) {
  PipelineConfig config = base;
  config.intrinsics.readout_ms = declared_ms;
  const AccuracyReport r =
      testing::run_scenario("drive", testing::accuracy_frames(frames), kSeed + 16, mode,
                            /*filter=*/true, config, also, 25.0);
  print_row("drive, 25 ms readout, told " + std::to_string(static_cast<int>(declared_ms)) +
                " ms, filtered, " + std::string(to_string(mode)),
            r);
  return r;
}

TEST(Accuracy, ThesisModesThroughARollingShutterUseTheFiltersMotion) {
  // Measured at 300 frames (axes / barycentric): told 25 ms 0.32 / 0.28 mm
  // median, p99 1.6 / 2.3 mm, yaw p99 0.39 / 0.20 deg; told 0 ms p99 6.7 /
  // 16.6 mm, yaw p99 1.13 / 0.93 deg. A global shutter on a drive: p99
  // 1.8 / 1.2 mm, yaw p99 0.53 / 0.30 deg.
  struct Limit {
    PositioningMode mode;
    double median_mm, p99_mm, yaw_p99_deg;
  };
  for (const Limit& l : {Limit{PositioningMode::kChangeOfAxes, 0.5, 2.5, 0.6},
                         Limit{PositioningMode::kBarycentric, 0.45, 3.0, 0.3}}) {
    const AccuracyReport r = filtered_rolling_drive(l.mode, 25.0, 300);
    EXPECT_EQ(r.gross, 0) << to_string(l.mode);
    EXPECT_LE(r.median_error_mm, l.median_mm) << to_string(l.mode);
    EXPECT_LE(r.p99_error_mm, l.p99_mm) << to_string(l.mode);
    EXPECT_LE(r.yaw_p99_deg, l.yaw_p99_deg) << to_string(l.mode);
    // At the sanitizers' 60 frames: p99 1.04 / 0.75 mm told 25 ms against
    // 1.81 / 2.49 mm told 0 ms.
    const AccuracyReport unmodelled = filtered_rolling_drive(l.mode, 0.0, 300);
    EXPECT_GE(unmodelled.p99_error_mm, 1.5 * r.p99_error_mm) << to_string(l.mode);
  }
}

// Scores only the frames that measured a pose (not those the filter
// coasted through without a marker).
class MeasuredFramesSink final : public PoseSink {
 public:
  explicit MeasuredFramesSink(double grid_m) : acc_(grid_m) {}
  void consume(const Localization& loc) override {
    if (loc.frame.has_ground_truth && loc.measured.valid)
      acc_.add(loc.frame.ground_truth, true, loc.published);
  }
  AccuracyReport report() const { return acc_.report(); }

 private:
  AccuracyAccumulator acc_;
};

TEST(Accuracy, OneOrTwoMarkersThroughARollingShutterUseTheFiltersMotion) {
  // A long lens (fx 1400 px) sees one or two markers at a time: too few rows
  // for lsq to tell the motion, so it holds the filter's.
  PipelineConfig narrow;
  narrow.intrinsics.fx = narrow.intrinsics.fy = 1400.0;
  MeasuredFramesSink told(narrow.layout.grid_m), unmodelled(narrow.layout.grid_m);
  const AccuracyReport published =
      filtered_rolling_drive(PositioningMode::kAuto, 25.0, 300, narrow, &told);
  filtered_rolling_drive(PositioningMode::kAuto, 0.0, 300, narrow, &unmodelled);
  const AccuracyReport r = told.report(), before = unmodelled.report();
  // Every published pose, the filter's predictions through up to 13 frames
  // without a marker included: none grossly wrong, since a prediction is
  // withheld once a gross error lies within two of its sds (before: 12
  // gross, p99 68 mm, yaw p99 44.5 deg). Measured at 300 frames: 173 of
  // 176 frames with a whole marker, 0.13 / 2.73 mm; at the sanitizers' 60
  // frames 10 of 11.
  EXPECT_EQ(published.gross, 0);
  EXPECT_GE(published.availability, 0.9);
  EXPECT_LE(published.p99_error_mm, 4.0);
  print_row("narrow drive, frames with a marker, told 25 ms", r);
  print_row("narrow drive, frames with a marker, told 0 ms", before);
  // Measured at 300 frames (170 with a marker): median 0.14 mm, p99 2.6 mm,
  // yaw p99 0.44 deg; told 0 ms: 1.90 / 12.5 mm, 2.4 deg. At the
  // sanitizers' 60 frames (10 with a marker): median 0.16 against 1.08 mm.
  EXPECT_GE(r.valid, 10);
  EXPECT_EQ(r.gross, 0);
  EXPECT_LE(r.median_error_mm, 0.3);
  EXPECT_LE(r.p99_error_mm, 4.0);
  EXPECT_GE(before.median_error_mm, 3.0 * r.median_error_mm)
      << "the test must see a rolling shutter";
}

// A still robot: the image is the same with or without a rolling shutter,
// and a readout declared for it (or for a global-shutter camera) must not
// cost accuracy: the motion is estimated as about zero.
TEST(Accuracy, ADeclaredReadoutDoesNoHarmToAStillRobot) {
  PipelineConfig told;
  told.intrinsics.readout_ms = 25.0;
  const int frames = testing::accuracy_frames(150);
  const AccuracyReport global =
      testing::run_scenario("nominal", frames, kSeed + 17, PositioningMode::kAuto);
  const AccuracyReport r =
      testing::run_scenario("nominal", frames, kSeed + 17, PositioningMode::kAuto, false, told);
  print_row("nominal, still, told 25 ms readout", r);
  // Measured at 150 frames, told 25 ms: 0.05 / 0.29 mm, yaw p99 0.021 deg.
  EXPECT_EQ(r.availability, global.availability);
  EXPECT_EQ(r.gross, 0);
  EXPECT_LE(r.median_error_mm, global.median_error_mm + 0.02);
  EXPECT_LE(r.p99_error_mm, 0.4);
  EXPECT_LE(r.yaw_p99_deg, 0.03);
}

// The thesis reports its modes at its static test points as the share of
// samples within ±0.05 grid units per axis: Barycentric 89–98%, Change of
// Axes 90–100%. Ours must be at least the thesis's best on both axes.
void expect_thesis_mode(PositioningMode mode, double min_within_per_axis, double max_median_mm,
                        double max_p99_mm, double max_yaw_p99_deg) {
  const AccuracyReport r =
      testing::run_scenario("thesis_points", testing::accuracy_frames(200), kSeed, mode);
  print_row("thesis points (" + std::string(to_string(mode)) + ")", r);
  EXPECT_EQ(r.availability, 1.0);
  EXPECT_GE(r.within_x, min_within_per_axis);
  EXPECT_GE(r.within_y, min_within_per_axis);
  EXPECT_EQ(r.mode_count[static_cast<int>(mode)], r.valid);
  EXPECT_LE(r.median_error_mm, max_median_mm);
  EXPECT_LE(r.p99_error_mm, max_p99_mm);
  EXPECT_LE(r.yaw_p99_deg, max_yaw_p99_deg);
  EXPECT_EQ(r.gross, 0);
}

TEST(Accuracy, ChangeOfAxesAtThesisPointsAtLeastMatchesThesis) {
  // One marker, the one nearest the image centre: a heavy tail, so the limits
  // come from 1000 frames (0.39 / 5.14 mm, yaw p99 0.86 deg; 200 frames gave
  // 0.34 / 1.77 mm, 0.26 deg).
  expect_thesis_mode(PositioningMode::kChangeOfAxes, 1.0, 0.78, 10.3, 1.73);
}

TEST(Accuracy, BarycentricAtThesisPointsAtLeastMatchesThesis) {
  // Measured: 0.06 / 0.14 mm, yaw p99 0.21 deg.
  expect_thesis_mode(PositioningMode::kBarycentric, 1.0, 0.12, 0.28, 0.42);
}

}  // namespace
}  // namespace ceilpose
