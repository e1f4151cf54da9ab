// The one frame path: refusals named where they are decided, the filter and
// the fix state, and every frame counted once in the refusal histogram.
#include "pipeline/localizer.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sim/renderer.h"
#include "tests/support/alloc_count.h"

namespace ceilpose {
namespace {

constexpr int64_t kFrameNs = 33'333'333;

class LocalizerTest : public ::testing::Test {
 protected:
  Image frame_at(const Pose2D& robot) {
    Image image;
    renderer_.render(robot, config_.mount, sim::Effects{}, 1, &image);
    return image;
  }
  FrameInfo next_frame() {
    FrameInfo info;
    info.index = index_++;
    info.timestamp_ns = index_ * kFrameNs;
    return info;
  }

  PipelineConfig config_;
  sim::Renderer renderer_{sim::SceneOptions{}};
  Image black_{640, 480, PixelFormat::kRgb24};
  int64_t index_ = 0;
};

TEST_F(LocalizerTest, UnfilteredPublishesTheMeasurementAndNamesEachRefusal) {
  Localizer localizer(with_mode(config_, PositioningMode::kAuto, false));
  const Pose2D robot{2.0, 2.0, 0.4};
  const Image ceiling = frame_at(robot);

  const Localization& ok = localizer.localize(ceiling.view(), next_frame());
  ASSERT_TRUE(ok.published.valid);
  EXPECT_FALSE(ok.filtered);
  EXPECT_EQ(ok.refusal, Refusal::kNone);
  EXPECT_EQ(ok.fix, FixState::kOk);
  EXPECT_EQ(ok.frame.index, 0);
  EXPECT_GT(ok.markers_decoded, 3);
  EXPECT_LT(std::hypot(ok.published.pose.x_m - robot.x_m, ok.published.pose.y_m - robot.y_m),
            0.002);
  EXPECT_GT(ok.localize_ns, 0);

  const Localization& dark = localizer.localize(black_.view(), next_frame());
  EXPECT_FALSE(dark.published.valid);
  EXPECT_EQ(dark.refusal, Refusal::kNoMarkers);
  EXPECT_EQ(dark.published.refusal, Refusal::kNoMarkers);
  EXPECT_EQ(dark.fix, FixState::kLost) << "no filter to coast on";

  const Image small(320, 240, PixelFormat::kRgb24);
  const Localization& unusable = localizer.localize(small.view(), next_frame());
  EXPECT_EQ(unusable.refusal, Refusal::kUnusableFrame);

  const RefusalHistogram& h = localizer.refusals();
  EXPECT_EQ(h[Refusal::kNone], 1u);
  EXPECT_EQ(h[Refusal::kNoMarkers], 1u);
  EXPECT_EQ(h[Refusal::kUnusableFrame], 1u);
  EXPECT_EQ(h[Refusal::kWrongHeights], 0u);
}

TEST_F(LocalizerTest, FilteredCoastsThroughAMissingFrameThenLosesTheFix) {
  config_.filter.predict_timeout_ms = 100.0;  // three frames
  Localizer localizer(with_mode(config_, PositioningMode::kAuto, true));
  const Localization& none = localizer.localize(black_.view(), next_frame());
  EXPECT_EQ(none.fix, FixState::kNone) << "no fix since start";
  EXPECT_EQ(none.published.refusal, Refusal::kNoMarkers);

  const Image ceiling = frame_at({1.5, 2.5, -1.0});
  ASSERT_TRUE(localizer.localize(ceiling.view(), next_frame()).published.valid);

  const Localization& coast = localizer.localize(black_.view(), next_frame());
  EXPECT_TRUE(coast.filtered);
  EXPECT_TRUE(coast.published.valid);
  EXPECT_TRUE(coast.coasting());
  EXPECT_EQ(coast.fix, FixState::kCoasting);
  EXPECT_EQ(coast.refusal, Refusal::kNoMarkers) << "the measurement's reason is kept";
  EXPECT_EQ(coast.published.refusal, Refusal::kNone) << "the published pose is not refused";

  const Localization* last = nullptr;
  for (int k = 0; k < 5; ++k) last = &localizer.localize(black_.view(), next_frame());
  EXPECT_FALSE(last->published.valid);
  EXPECT_EQ(last->fix, FixState::kLost);
  EXPECT_EQ(last->published.refusal, Refusal::kNoMarkers);
  EXPECT_EQ(localizer.refusals()[Refusal::kNoMarkers], 7u);
  EXPECT_EQ(localizer.refusals()[Refusal::kNone], 1u);
}

// Issue 28, defect 4: a filter whose numbers overflow (here an initial
// velocity sd of 1e200 m/s, whose variance is infinite) publishes no pose,
// named, rather than a pose with an infinite covariance; and it starts again.
TEST_F(LocalizerTest, ANonFiniteFilterStateIsNeverPublished) {
  config_.filter.init_velocity_sigma_mps = 1e200;
  Localizer localizer(with_mode(config_, PositioningMode::kAuto, true));
  const Image ceiling = frame_at({1.5, 2.5, -1.0});
  for (int k = 0; k < 3; ++k) {
    const Localization& loc = localizer.localize(ceiling.view(), next_frame());
    EXPECT_TRUE(loc.measured.valid);
    EXPECT_FALSE(loc.published.valid) << "frame " << k;
    EXPECT_EQ(loc.published.refusal, Refusal::kFilterRejected);
    EXPECT_EQ(loc.refusal, Refusal::kFilterRejected);
    EXPECT_FALSE(loc.motion.valid);
  }
}

TEST_F(LocalizerTest, WrongHeightsAreRefusedWhereThePositionerDecides) {
  // The configuration's lens sits 0.4 m lower than the camera that rendered
  // the frame: the markers' spacing says so.
  PipelineConfig wrong = config_;
  wrong.mount.lens_height_m = config_.mount.lens_height_m - 0.4;
  Localizer localizer(with_mode(wrong, PositioningMode::kAuto, false));
  const Localization& loc = localizer.localize(frame_at({2.0, 2.0, 0.0}).view(), next_frame());
  EXPECT_FALSE(loc.published.valid);
  EXPECT_EQ(loc.refusal, Refusal::kWrongHeights);
  EXPECT_LT(loc.measured.depth_scale, 0.9) << "the true lens-to-ceiling distance is shorter";
}

TEST_F(LocalizerTest, ReconfigureSwitchesModeAndFilterBetweenFrames) {
  Localizer localizer(with_mode(config_, PositioningMode::kAuto, true));
  const Image ceiling = frame_at({2.0, 2.0, 0.4});
  EXPECT_EQ(localizer.localize(ceiling.view(), next_frame()).published.mode,
            PositioningMode::kLeastSquares);
  localizer.reconfigure(with_mode(config_, PositioningMode::kChangeOfAxes, false), true);
  const Localization& axes = localizer.localize(ceiling.view(), next_frame());
  EXPECT_FALSE(axes.filtered);
  EXPECT_EQ(axes.published.mode, PositioningMode::kChangeOfAxes);
}

// localize() promises no allocation per frame with everything on: the
// filter, a rolling shutter (the readout motion it predicts and lsq's motion
// unknowns) and a camera that moves, with a missing frame in between.
TEST_F(LocalizerTest, LocalizeWithFilterAndRollingShutterAllocatesNothing) {
  PipelineConfig config = with_mode(config_, PositioningMode::kAuto, true);
  config.intrinsics.readout_ms = 25.0;
  // The alternating poses leave the prediction's yaw sd past the coasting
  // bound, and jump back and forth as no robot does, which the gate would
  // refuse: both lifted, so that every frame's published pose is timed.
  config.filter.coast_max_sd_m = config.filter.coast_max_yaw_sd_rad = 1e9;
  config.filter.gate_chi2 = 1e9;
  Localizer localizer(config);
  const Image a = frame_at({2.0, 2.0, 0.4}), b = frame_at({2.02, 2.0, 0.41});
  for (int k = 0; k < 4; ++k) localizer.localize((k % 2 ? b : a).view(), next_frame());  // warm-up
  test::start_counting_allocations();
  int valid = 0;
  for (int k = 0; k < 6; ++k) {
    const Image& image = k == 3 ? black_ : k % 2 ? b : a;
    valid += localizer.localize(image.view(), next_frame()).published.valid ? 1 : 0;
  }
  EXPECT_EQ(test::stop_counting_allocations(), 0);
  EXPECT_EQ(valid, 6) << "coasting through the black frame counts as published";
}

TEST(RefusalNames, AreSnakeCaseUniqueAndStable) {
  // The names are SPEC §5's; the values are in the shared-memory and DDS
  // layouts, so neither may change silently.
  EXPECT_EQ(to_string(Refusal::kNone), "none");
  EXPECT_EQ(to_string(Refusal::kUnusableFrame), "unusable_frame");
  EXPECT_EQ(to_string(Refusal::kNoMarkers), "no_markers");
  EXPECT_EQ(to_string(Refusal::kUnreadableMarkers), "unreadable_markers");
  EXPECT_EQ(to_string(Refusal::kInconsistentMarkers), "inconsistent_markers");
  EXPECT_EQ(to_string(Refusal::kWrongHeights), "wrong_heights");
  EXPECT_EQ(to_string(Refusal::kSolverRejected), "solver_rejected");
  EXPECT_EQ(static_cast<int>(Refusal::kWrongHeights), 8);
  for (int i = 0; i < kRefusalCount; ++i) {
    const std::string_view name = refusal_name(i);
    for (char c : name) EXPECT_TRUE((c >= 'a' && c <= 'z') || c == '_') << name;
    for (int j = i + 1; j < kRefusalCount; ++j) EXPECT_NE(name, refusal_name(j));
    EXPECT_FALSE(describe(static_cast<Refusal>(i)).empty());
  }
  EXPECT_EQ(refusal_name(kRefusalCount), "unknown");
  EXPECT_EQ(refusal_name(-1), "unknown");
}

}  // namespace
}  // namespace ceilpose
