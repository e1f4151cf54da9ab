// The named scenario sets: complete, deterministic, and each what its
// description promises.
#include "sim/scenarios.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>

#include "sim/trajectory.h"
#include "sim/visibility.h"

namespace ceilpose::sim {
namespace {

Scenario make(std::string_view name, int frames, uint64_t seed = 1) {
  Result<Scenario> s = make_scenario(name, SceneOptions{}, frames, seed);
  EXPECT_TRUE(s.ok()) << (s.ok() ? "" : s.error().message);
  return s.ok() ? *s : Scenario{};
}

TEST(Scenarios, CatalogHasEveryRequiredSet) {
  std::set<std::string> names;
  for (const auto& [name, description] : scenario_catalog()) {
    EXPECT_FALSE(description.empty()) << name;
    names.insert(name);
  }
  for (const char* required : {"thesis_points", "random", "trajectory", "gain", "gradient",
                               "colour_cast", "noise", "blur", "motion_blur", "jpeg", "fixtures",
                               "occlusion", "clutter", "stress", "tilt", "edges", "nominal"})
    EXPECT_TRUE(names.count(required)) << required;
}

TEST(Scenarios, EverySetBuildsTheRequestedFramesWithIncreasingTimestamps) {
  for (const auto& [name, description] : scenario_catalog()) {
    const Scenario s = make(name, 12);
    ASSERT_EQ(s.frames.size(), 12u) << name;
    for (size_t i = 1; i < s.frames.size(); ++i)
      EXPECT_EQ(s.frames[i].timestamp_ns - s.frames[i - 1].timestamp_ns, kScenarioFramePeriod_ns)
          << name;
  }
}

TEST(Scenarios, SameSeedGivesTheSameFrames) {
  const Scenario a = make("stress", 20, 5), b = make("stress", 20, 5);
  for (size_t i = 0; i < a.frames.size(); ++i) {
    EXPECT_EQ(a.frames[i].pose.x_m, b.frames[i].pose.x_m);
    EXPECT_EQ(a.frames[i].effects.gain, b.frames[i].effects.gain);
    EXPECT_EQ(a.frames[i].seed, b.frames[i].seed);
  }
}

TEST(Scenarios, AnotherSeedGivesOtherPoses) {
  const Scenario a = make("random", 5, 5), b = make("random", 5, 6);
  EXPECT_NE(a.frames[0].pose.x_m, b.frames[0].pose.x_m);
}

TEST(Scenarios, UnknownNameIsAnErrorThatNamesIt) {
  const Result<Scenario> s = make_scenario("no_such_set", SceneOptions{}, 5, 1);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("no_such_set"), std::string::npos);
}

TEST(Scenarios, ZeroFramesIsAnError) {
  EXPECT_FALSE(make_scenario("random", SceneOptions{}, 0, 1).ok());
}

TEST(Scenarios, ThesisPointsVisitTheFivePointsInGridUnits) {
  const Scenario s = make("thesis_points", 25);
  const double g = CeilingLayout{}.grid_m;
  std::set<std::pair<double, double>> points;
  for (const ScenarioFrame& f : s.frames)
    points.insert({std::round(f.pose.x_m / g * 10) / 10, std::round(f.pose.y_m / g * 10) / 10});
  const std::set<std::pair<double, double>> expected{
      {1.5, 1.5}, {1.5, 2.0}, {1.5, 2.5}, {2.0, 2.5}, {2.5, 2.5}};
  EXPECT_EQ(points, expected);
}

TEST(Scenarios, RandomPosesStayOverTheGridInterior) {
  const double span = 7 * CeilingLayout{}.grid_m;
  for (const ScenarioFrame& f : make("random", 200).frames) {
    EXPECT_GE(f.pose.x_m, 0.0);
    EXPECT_LE(f.pose.x_m, span);
    EXPECT_GE(f.pose.y_m, 0.0);
    EXPECT_LE(f.pose.y_m, span);
  }
}

TEST(Scenarios, TrajectoryMovesAtWalkingSpeedAndTurnsSmoothly) {
  const Scenario s = make("trajectory", 600);  // 24 m: once round the loop and on
  for (size_t i = 1; i < s.frames.size(); ++i) {
    const Pose2D& a = s.frames[i - 1].pose;
    const Pose2D& b = s.frames[i].pose;
    const double dt = (s.frames[i].timestamp_ns - s.frames[i - 1].timestamp_ns) * 1e-9;
    EXPECT_NEAR(std::hypot(b.x_m - a.x_m, b.y_m - a.y_m) / dt, kWalkingSpeed_mps, 0.05);
    EXPECT_LT(std::abs(wrap_angle_rad(b.yaw_rad - a.yaw_rad)), 0.1);
    // The robot faces along its path.
    EXPECT_LT(std::abs(wrap_angle_rad(std::atan2(b.y_m - a.y_m, b.x_m - a.x_m) - b.yaw_rad)), 0.1);
  }
}

TEST(Scenarios, TiltStaysWithinThreeDegrees) {
  double largest = 0.0;
  for (const ScenarioFrame& f : make("tilt", 200).frames) {
    const double tilt = std::hypot(f.mount.tilt_x_rad, f.mount.tilt_y_rad);
    EXPECT_LE(tilt, 3.0 * std::numbers::pi / 180 + 1e-12);
    largest = std::max(largest, tilt);
  }
  EXPECT_GT(largest, 2.5 * std::numbers::pi / 180);
}

TEST(Scenarios, EdgeFramesShowAtMostTwoWholeMarkers) {
  const SceneOptions options;
  std::set<int> counts;
  for (const ScenarioFrame& f : make("edges", 60).frames) {
    const int n = count_whole_markers(options, f.pose, f.mount);
    EXPECT_LE(n, 2);
    counts.insert(n);
  }
  EXPECT_GE(counts.size(), 2u);
}

TEST(Scenarios, NominalNoiseIsAtMostThreeLevels) {
  for (const ScenarioFrame& f : make("nominal", 100).frames) {
    EXPECT_LE(f.effects.read_noise_sigma, 3.0);
    EXPECT_EQ(f.effects.shot_noise_scale, 0.0);
  }
}

TEST(Scenarios, StressCombinesTheIssueThreeLevels) {
  for (const ScenarioFrame& f : make("stress", 100).frames) {
    const Effects& e = f.effects;
    EXPECT_GE(e.gain, 0.45);
    EXPECT_LE(e.gain, 1.6);
    for (double m : e.white_balance) {
      EXPECT_GE(m, 0.75);
      EXPECT_LE(m, 1.25);
    }
    EXPECT_EQ(e.read_noise_sigma, 6.0);
    EXPECT_GT(e.defocus_sigma_px, 0.0);
    EXPECT_EQ(e.jpeg_quality, 60);
    EXPECT_EQ(e.occlusion_fraction, 0.0);
  }
}

}  // namespace
}  // namespace ceilpose::sim
