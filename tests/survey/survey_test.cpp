// The survey of SPEC §10 against the simulator's truth: a hand-laid ceiling
// (markers 15 mm and 1° off, one 50 mm off, one missing, one code printed
// twice) walked by the survey_walk set, then other frames under the same
// ceiling localized against the map it made. Full frame counts under the
// sanitizers too: a survey of 40 frames sees too little to be held to the
// limits (~2 min under ASan for the whole file).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>

#include "pipeline/accuracy_metrics.h"
#include "pipeline/localizer.h"
#include "sim/laid_ceiling.h"
#include "sim/renderer.h"
#include "sim/scenarios.h"
#include "survey/bundle_adjustment.h"

namespace ceilpose {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct Walk {
  std::vector<SurveyFrame> frames;  // the survey's observations
  AccuracyReport accuracy;          // of the per-frame poses, when scored
};

// Renders `count` frames of `scenario` under `laid` through `true_camera`
// and localizes them with `config` (its camera is the declared one):
// survey frames, and SPEC §6 accuracy against the truth.
Walk run(const std::string& scenario, int count, uint64_t seed,
         std::shared_ptr<const sim::LaidCeiling> laid, const PipelineConfig& config,
         const CameraIntrinsics& true_camera) {
  sim::SceneOptions scene{config.layout, true_camera, seed, laid};
  auto set = sim::make_scenario(scenario, scene, count, seed);
  EXPECT_TRUE(set) << set.error().message;
  sim::Renderer renderer(scene);
  Localizer localizer(with_mode(config, PositioningMode::kLeastSquares, false));
  AccuracyAccumulator accuracy(config.layout.grid_m);
  Walk out;
  Image image;
  for (const sim::ScenarioFrame& f : set->frames) {
    renderer.render(f.pose, config.mount, f.effects, f.seed, &image);
    const Localization& loc =
        localizer.localize(image.view(), FrameInfo{f.timestamp_ns, -1, false, {}});
    accuracy.add(f.pose, true, loc.measured);
    if (!loc.measured.valid) continue;
    SurveyFrame frame{loc.frame.timestamp_ns, loc.measured.pose, {}};
    for (const MarkerObservation& m : loc.markers)
      if (m.whole) frame.markers.push_back(m);
    out.frames.push_back(std::move(frame));
  }
  out.accuracy = accuracy.report();
  return out;
}

struct MapError {
  int missing = 0, invented = 0;
  double rms_m = 0.0, max_m = 0.0, yaw_rms_rad = 0.0, yaw_max_rad = 0.0;
};

MapError compare(const CeilingMap& truth, const CeilingMap& map) {
  MapError e;
  int n = 0;
  for (int j = 0; j < truth.codes(); ++j)
    for (int i = 0; i < truth.codes(); ++i) {
      const MarkerPlacement* t = truth.find(i, j);
      const MarkerPlacement* m = map.find(i, j);
      if (t != nullptr && m == nullptr) ++e.missing;
      if (t == nullptr && m != nullptr) ++e.invented;
      if (t == nullptr || m == nullptr) continue;
      const double d = std::hypot(m->x_m - t->x_m, m->y_m - t->y_m);
      const double y = std::abs(wrap_angle_rad(m->yaw_rad - t->yaw_rad));
      e.rms_m += d * d;
      e.yaw_rms_rad += y * y;
      e.max_m = std::max(e.max_m, d);
      e.yaw_max_rad = std::max(e.yaw_max_rad, y);
      ++n;
    }
  e.rms_m = std::sqrt(e.rms_m / n);
  e.yaw_rms_rad = std::sqrt(e.yaw_rms_rad / n);
  return e;
}

class Survey : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    sim::HandLaidOptions o;
    o.seed = 7;
    laid_ = std::make_shared<const sim::LaidCeiling>(sim::LaidCeiling::hand_laid({}, o));
  }
  static std::shared_ptr<const sim::LaidCeiling> laid_;
  PipelineConfig config_;
  SurveyOptions options_;
};
std::shared_ptr<const sim::LaidCeiling> Survey::laid_;

TEST_F(Survey, RecoversAHandLaidCeilingAndNamesTheCodePrintedTwice) {
  const Walk walk = run("survey_walk", 200, 11, laid_, config_, config_.intrinsics);
  auto report = survey_ceiling(config_, walk.frames, options_);
  ASSERT_TRUE(report) << report.error().message;
  const MapError e = compare(laid_->truth_map(), report->map);
  EXPECT_EQ(e.invented, 0);
  EXPECT_EQ(report->groups, 1);
  // Measured (200 frames): RMS 0.075 mm, max 0.27 mm, yaw RMS 0.062°, max 0.26°.
  EXPECT_LE(e.rms_m, 0.00015);
  EXPECT_LE(e.max_m, 0.0005);
  EXPECT_LE(e.yaw_rms_rad, 0.12 * kDeg);
  EXPECT_LE(e.yaw_max_rad, 0.5 * kDeg);
  EXPECT_EQ(e.missing, 0) << "every marker on the ceiling is mapped (the fallen one is not on it)";
  // The one 50 mm off is found where it is, not pulled to its spot.
  EXPECT_NEAR(report->largest_shift_m, 0.05, 0.01);
  // Node (1, 2) shows code (2, 1) (the ceiling's notes): reported there.
  ASSERT_EQ(report->duplicates.size(), 1u);
  const SurveyDuplicate& d = report->duplicates[0];
  EXPECT_EQ(d.code_i, 2);
  EXPECT_EQ(d.code_j, 1);
  EXPECT_NEAR(d.x_m, 1 * 0.6096, 0.05);
  EXPECT_NEAR(d.y_m, 2 * 0.6096, 0.05);
  EXPECT_LT(report->rms_px, 0.1);
  EXPECT_GT(report->initial_rms_px, 3.0) << "the nominal grid should not fit this ceiling";

  // Five frames whose poses are 0.25 m off see each of their markers that
  // far from its spot, yet nearest its own node: not a second print (that
  // is glued at another node), the frames' poses. Before they were told
  // apart, every code of those frames was "printed twice".
  std::vector<SurveyFrame> off = walk.frames;
  int off_sightings = 0;
  for (size_t f = 50; f < 55; ++f) {
    off[f].robot.x_m += 0.25;
    off_sightings += static_cast<int>(off[f].markers.size());
  }
  ASSERT_GE(off_sightings, 15);
  auto off_report = survey_ceiling(config_, off, options_);
  ASSERT_TRUE(off_report) << off_report.error().message;
  ASSERT_EQ(off_report->duplicates.size(), 1u);
  EXPECT_EQ(off_report->duplicates[0].code_i, 2);
  EXPECT_EQ(off_report->duplicates[0].code_j, 1);
  EXPECT_LE(compare(laid_->truth_map(), off_report->map).max_m, 0.0005);

  // Other frames under the same ceiling, against the map and without it.
  const Walk test = run("nominal", 100, 5, laid_, config_, config_.intrinsics);
  PipelineConfig mapped = config_;
  mapped.map = std::make_shared<const CeilingMap>(report->map);
  const Walk located = run("nominal", 100, 5, laid_, mapped, config_.intrinsics);
  const AccuracyReport& a = located.accuracy;
  // Measured (300 frames): median 0.06 mm, p99 0.20 mm, 0 gross, NEES 2.2;
  // without the map median 9 mm, NEES 3.4.
  EXPECT_LE(a.median_error_mm, 0.12);
  EXPECT_LE(a.p99_error_mm, 0.45);
  EXPECT_EQ(a.gross, 0);
  EXPECT_GE(a.availability, 0.99);
  EXPECT_GE(a.mean_nees, 1.0);
  EXPECT_LE(a.mean_nees, 5.0);
  EXPECT_GT(test.accuracy.median_error_mm, 4.0) << "without the map the offsets show";
  EXPECT_GE(test.accuracy.mean_nees, 1.0);
  EXPECT_LE(test.accuracy.mean_nees, 5.0);
}

// A marker glued 0.25 m off its spot: positioning's grid consistency
// (0.3 of a 0.61 m unit, 0.18 m) refuses it in every frame, so the frames'
// poses come from the other markers, and its sightings lie more than 0.2 m
// from its spot, yet nearest its own node. It reaches past its node's half
// grid, which the simulator now draws (before, its far end was clipped:
// seeds 7, 9, 10, 11 and 14 never decoded it, 12 and 13 mapped its clipped
// centroid 15-16 mm off). Measured (2026-12-07, seeds 7-14): mapped in
// every one, the map's largest error 0.25-0.38 mm, RMS 0.070-0.102 mm; this
// seed 0.384 and 0.088 mm.
TEST_F(Survey, MapsAMarkerGluedFarOffItsSpot) {
  sim::HandLaidOptions o;
  o.seed = 12;
  o.outlier_m = 0.25;
  const auto laid = std::make_shared<const sim::LaidCeiling>(sim::LaidCeiling::hand_laid({}, o));
  const Walk walk = run("survey_walk", 200, 11, laid, config_, config_.intrinsics);
  auto report = survey_ceiling(config_, walk.frames, options_);
  ASSERT_TRUE(report) << report.error().message;
  const MapError e = compare(laid->truth_map(), report->map);
  EXPECT_EQ(e.invented, 0);
  EXPECT_EQ(e.missing, 0) << "the marker far off its spot is on the ceiling: mapped";
  EXPECT_LE(e.max_m, 0.0005);
  EXPECT_LE(e.rms_m, 0.00015);
  EXPECT_NEAR(report->largest_shift_m, 0.240, 0.005) << "found where it is";
  EXPECT_EQ(report->duplicates.size(), 1u) << "only the code printed twice";
}

TEST_F(Survey, EstimatesAnUncalibratedCamerasFocalLengthAndDistortion) {
  CameraIntrinsics truth = config_.intrinsics;
  truth.fx = truth.fy = 530.0 * 1.025;
  truth.distortion[0] = -0.08;
  const Walk walk = run("survey_walk", 200, 11, laid_, config_, truth);
  SurveyOptions options = options_;
  options.estimate_intrinsics = true;
  auto first = survey_ceiling(config_, walk.frames, options);
  ASSERT_TRUE(first) << first.error().message;
  // Decoded again with the camera found, as `ceilposectl survey` does.
  PipelineConfig found = config_;
  found.intrinsics = first->intrinsics;
  const Walk again = run("survey_walk", 200, 11, laid_, found, truth);
  auto report = survey_ceiling(found, again.frames, options);
  ASSERT_TRUE(report) << report.error().message;
  const CameraIntrinsics& k = report->intrinsics;
  // Measured: fx 543.89 (true 543.25, +0.12 %: the grid's scale through 62
  // markers 15 mm off), k1 -0.0802.
  EXPECT_NEAR(k.fx, truth.fx, 0.003 * truth.fx);
  EXPECT_NEAR(k.fy, truth.fy, 0.003 * truth.fy);
  EXPECT_NEAR(k.distortion[0], -0.08, 0.004);
  EXPECT_DOUBLE_EQ(k.cx, config_.intrinsics.cx) << "the principal point is held";
  PipelineConfig calibrated = config_;
  calibrated.intrinsics = k;
  calibrated.map = std::make_shared<const CeilingMap>(report->map);
  const Walk located = run("nominal", 100, 5, laid_, calibrated, truth);
  // Measured (300 frames): median 2.1 mm, p99 3.5 mm (the scale left by the
  // grid prior), 0 gross.
  EXPECT_LE(located.accuracy.median_error_mm, 3.0);
  EXPECT_LE(located.accuracy.p99_error_mm, 5.0);
  EXPECT_EQ(located.accuracy.gross, 0);
}

TEST_F(Survey, TwoPassesThatNeverMeetAreMappedAndWarnedAbout) {
  const Walk walk = run("survey_two_passes", 150, 13, laid_, config_, config_.intrinsics);
  auto report = survey_ceiling(config_, walk.frames, options_);
  ASSERT_TRUE(report) << report.error().message;
  EXPECT_EQ(report->groups, 2);
  const MapError e = compare(laid_->truth_map(), report->map);
  EXPECT_EQ(e.invented, 0);
  EXPECT_GE(report->map.present_count(), 40);
  // Each part is exact within itself; where one sits against the other
  // rests on the 5 cm prior over ~30 markers (measured RMS 4.4 mm), and the
  // sigmas say so.
  EXPECT_LE(e.rms_m, 0.015);
  double median_sigma = 0.0;
  std::vector<double> sigmas;
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i)
      if (const MarkerPlacement* p = report->map.find(i, j)) sigmas.push_back(p->sigma_m);
  std::nth_element(sigmas.begin(), sigmas.begin() + sigmas.size() / 2, sigmas.end());
  median_sigma = sigmas[sigmas.size() / 2];
  EXPECT_GT(median_sigma, 0.002);
}

// issue 27: a survey of a robot that did not move (or of one frame
// repeated) wrote a map whose sigmas were 100-1000x smaller than its errors.
TEST_F(Survey, FramesFromOnePlaceAreRefusedSayingSo) {
  const Walk walk = run("survey_walk", 40, 11, laid_, config_, config_.intrinsics);
  ASSERT_GT(walk.frames.size(), 20u);
  // The same frame thirty times, and thirty frames a tenth of a millimetre
  // apart (a stationary robot's noise).
  std::vector<SurveyFrame> same(30, walk.frames[10]);
  std::vector<SurveyFrame> still = same;
  for (size_t k = 0; k < still.size(); ++k) still[k].robot.x_m += 1e-4 * static_cast<double>(k);
  for (const auto* frames : {&same, &still}) {
    auto report = survey_ceiling(config_, *frames, options_);
    ASSERT_FALSE(report);
    EXPECT_NE(report.error().message.find("saw the ceiling from 1 place(s)"), std::string::npos)
        << report.error().message;
  }
  // The walk those frames came from is surveyed.
  auto report = survey_ceiling(config_, walk.frames, options_);
  ASSERT_TRUE(report) << report.error().message;
  EXPECT_GE(report->viewpoints, 20);
}

TEST_F(Survey, FramesThatSeeNoMarkerOftenEnoughAreAnErrorSayingWhy) {
  std::vector<SurveyFrame> frames(2);
  auto report = survey_ceiling(config_, frames, options_);
  ASSERT_FALSE(report);
  EXPECT_NE(report.error().message.find("no marker was decoded in 3 or more of the 2 frames"),
            std::string::npos)
      << report.error().message;
}

}  // namespace
}  // namespace ceilpose
