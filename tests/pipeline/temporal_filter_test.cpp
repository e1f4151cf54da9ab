#include "pipeline/temporal_filter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace ceilpose {
namespace {

constexpr int64_t kFrameNs = 33'333'333;  // 30 fps

PoseEstimate measurement(double x, double y, double yaw, double sigma_m = 0.005,
                         double sigma_yaw_rad = 0.01) {
  PoseEstimate m;
  m.valid = true;
  m.pose = {x, y, yaw};
  m.covariance = {
      sigma_m * sigma_m, 0, 0, 0, sigma_m * sigma_m, 0, 0, 0, sigma_yaw_rad * sigma_yaw_rad};
  m.mode = PositioningMode::kLeastSquares;
  m.markers = 9;
  return m;
}

TEST(TemporalFilter, InvalidUntilFirstValidMeasurement) {
  TemporalFilter filter{FilterParams{}};
  EXPECT_FALSE(filter.update(PoseEstimate{}, 0).valid);
  const PoseEstimate out = filter.update(measurement(1.0, 2.0, 0.5), kFrameNs);
  ASSERT_TRUE(out.valid);
  EXPECT_DOUBLE_EQ(out.pose.x_m, 1.0);
  EXPECT_EQ(out.mode, PositioningMode::kLeastSquares);
}

TEST(TemporalFilter, SmoothsNoiseOfAStationaryRobot) {
  FilterParams params;  // process noise of a slow robot: smoothing dominates
  params.jerk_sigma_mps3 = 0.05;
  TemporalFilter filter{params};
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.005);
  double raw_sq = 0.0, filtered_sq = 0.0;
  int n = 0;
  for (int k = 0; k < 300; ++k) {
    const double dx = noise(rng);
    const PoseEstimate out = filter.update(measurement(1.0 + dx, 2.0, 0.3), k * kFrameNs);
    ASSERT_TRUE(out.valid);
    if (k < 30) continue;  // settling
    raw_sq += dx * dx;
    filtered_sq += (out.pose.x_m - 1.0) * (out.pose.x_m - 1.0);
    ++n;
  }
  EXPECT_LT(std::sqrt(filtered_sq / n), 0.6 * std::sqrt(raw_sq / n));
}

TEST(TemporalFilter, TracksConstantVelocityWithoutLag) {
  TemporalFilter filter{FilterParams{}};
  PoseEstimate out;
  for (int k = 0; k < 120; ++k) {
    const double t = k * kFrameNs * 1e-9;
    out = filter.update(measurement(0.5 * t, 1.0, 0.0), k * kFrameNs);
  }
  const double t_end = 119 * kFrameNs * 1e-9;
  EXPECT_NEAR(out.pose.x_m, 0.5 * t_end, 0.002);
}

// A rolling shutter's lone marker measures the robot when its row was
// exposed (time_offset_s after the frame): fused at that instant, the pose
// returned is still the frame's; taken as the frame's, it would be off by
// v·offset.
TEST(TemporalFilter, FusesAPoseAtItsRowsInstantAndAnswersForTheFrame) {
  TemporalFilter at_rows{FilterParams{}}, as_frame{FilterParams{}};
  constexpr double kSpeedMps = 1.5, kYawRateRadps = 2.0;
  PoseEstimate rows_out, frame_out;
  for (int k = 0; k < 60; ++k) {
    const double t_s = k * kFrameNs * 1e-9;
    const double offset_s = (k % 2 == 0 ? 1.0 : -1.0) * 0.010;  // the marker's row moves
    PoseEstimate m =
        measurement(kSpeedMps * (t_s + offset_s), 1.0, kYawRateRadps * (t_s + offset_s));
    m.time_offset_s = offset_s;
    rows_out = at_rows.update(m, k * kFrameNs);
    m.time_offset_s = 0.0;
    frame_out = as_frame.update(m, k * kFrameNs);
  }
  const double t_end_s = 59 * kFrameNs * 1e-9;
  EXPECT_NEAR(rows_out.pose.x_m, kSpeedMps * t_end_s, 0.0005);
  EXPECT_NEAR(rows_out.pose.yaw_rad, wrap_angle_rad(kYawRateRadps * t_end_s), 0.001);
  EXPECT_NEAR(at_rows.state().x[3], kSpeedMps, 0.02);
  EXPECT_GT(std::abs(frame_out.pose.x_m - kSpeedMps * t_end_s), 0.005)
      << "the offset must matter for the test to mean anything";
  // The state refers to the last measurement's instant.
  EXPECT_EQ(at_rows.state_time_ns(), 59 * kFrameNs - 10'000'000);
}

// A robot speeding up on a circle: the constant-acceleration model follows
// it without lag and its state carries the velocity, yaw rate and the
// centripetal acceleration a controller's prediction needs.
TEST(TemporalFilter, FollowsAnAcceleratingTurnAndEstimatesItsVelocity) {
  TemporalFilter filter{FilterParams{}};
  const double radius_m = 1.0;
  auto angle = [](double t) { return 0.2 * t + 0.25 * t * t; };  // speeds up
  PoseEstimate out;
  for (int k = 0; k < 90; ++k) {
    const double t = k * kFrameNs * 1e-9, a = angle(t);
    out = filter.update(measurement(radius_m * std::cos(a), radius_m * std::sin(a),
                                    a + std::numbers::pi / 2, 0.0002),
                        k * kFrameNs);
  }
  const double t = 89 * kFrameNs * 1e-9, a = angle(t), w = 0.2 + 0.5 * t;  // 1.68 rad/s
  ASSERT_TRUE(out.valid);
  EXPECT_NEAR(out.pose.x_m, radius_m * std::cos(a), 0.0005);
  EXPECT_NEAR(out.pose.y_m, radius_m * std::sin(a), 0.0005);
  const MotionState& s = filter.state();
  EXPECT_NEAR(s.x[3], -radius_m * w * std::sin(a), 0.01);
  EXPECT_NEAR(s.x[4], radius_m * w * std::cos(a), 0.01);
  EXPECT_NEAR(s.x[5], w, 0.01);
  // Centripetal acceleration w²r towards the centre (plus the tangential 0.5 m/s²).
  EXPECT_NEAR(s.x[6], -radius_m * w * w * std::cos(a) - 0.5 * std::sin(a), 0.2);
  EXPECT_NEAR(s.x[7], -radius_m * w * w * std::sin(a) + 0.5 * std::cos(a), 0.2);
  EXPECT_EQ(filter.stats().gated, 0u);
  EXPECT_EQ(filter.state_time_ns(), 89 * kFrameNs);
}

TEST(TemporalFilter, WrapsYawAcrossPi) {
  TemporalFilter filter{FilterParams{}};
  const double pi = std::numbers::pi;
  filter.update(measurement(1.0, 1.0, pi - 0.01), 0);
  const PoseEstimate out = filter.update(measurement(1.0, 1.0, -pi + 0.01), kFrameNs);
  ASSERT_TRUE(out.valid);
  // Between the two, across ±π — not near 0.
  EXPECT_GT(std::abs(out.pose.yaw_rad), pi - 0.02);
  EXPECT_EQ(filter.stats().gated, 0u);
}

// The coasting bounds lifted (these measurements' 0.01 rad yaw sd leaves a
// prediction's at 0.061 rad, past them): the gate alone.
FilterParams gate_alone() {
  FilterParams params;
  params.coast_max_sd_m = params.coast_max_yaw_sd_rad = 1e9;
  return params;
}

// A measurement 0.6 m from a robot standing still for a second: a decode
// gone wrong, or the robot picked up. The frame publishes nothing, not the
// prediction either; the next measurement that agrees is fused.
TEST(TemporalFilter, AGatedMeasurementsFramePublishesNoPose) {
  TemporalFilter filter{gate_alone()};
  for (int k = 0; k < 30; ++k) filter.update(measurement(1.0, 1.0, 0.0), k * kFrameNs);
  const PoseEstimate out = filter.update(measurement(1.6, 1.0, 0.0), 30 * kFrameNs);
  EXPECT_FALSE(out.valid) << "published a pose 0.6 m from the measurement";
  EXPECT_EQ(filter.stats().gated, 1u);
  const PoseEstimate next = filter.update(measurement(1.0, 1.0, 0.0), 31 * kFrameNs);
  ASSERT_TRUE(next.valid);
  EXPECT_NEAR(next.pose.x_m, 1.0, 0.005);
  EXPECT_EQ(filter.stats().gated, 1u);
}

// A robot set down 2 m away: no pose until the filter believes the new
// place (reinit_after_gated measurements there in a row), never the old one.
TEST(TemporalFilter, ReinitialisesAfterConsecutiveGatedMeasurements) {
  FilterParams params = gate_alone();
  params.reinit_after_gated = 4;
  TemporalFilter filter{params};
  for (int k = 0; k < 30; ++k) filter.update(measurement(1.0, 1.0, 0.0), k * kFrameNs);
  PoseEstimate out;
  for (int k = 30; k < 33; ++k) {
    out = filter.update(measurement(3.0, 1.0, 0.0), k * kFrameNs);
    EXPECT_FALSE(out.valid) << "frame " << k;
  }
  out = filter.update(measurement(3.0, 1.0, 0.0), 33 * kFrameNs);
  ASSERT_TRUE(out.valid);
  EXPECT_DOUBLE_EQ(out.pose.x_m, 3.0);
  EXPECT_EQ(filter.stats().reinitialisations, 1u);
  EXPECT_EQ(filter.stats().gated, 4u);
}

// Gated measurements that disagree with each other (two places 2 m apart,
// alternating: a wrong decode among them) do not restart the filter, however
// many in a row: the fifth gated one used to be believed, whatever it was.
// (Twelve frames: at predict_timeout_ms without a fused measurement the
// filter starts again from nothing, as at start-up.)
TEST(TemporalFilter, GatedMeasurementsThatDisagreeWithEachOtherNeverRestartIt) {
  TemporalFilter filter{gate_alone()};  // reinit_after_gated 5, timeout 500 ms
  for (int k = 0; k < 30; ++k) filter.update(measurement(1.0, 1.0, 0.0), k * kFrameNs);
  for (int k = 30; k < 42; ++k) {
    const double x = k % 2 == 0 ? 3.0 : 5.0;
    EXPECT_FALSE(filter.update(measurement(x, 1.0, 0.0), k * kFrameNs).valid) << "frame " << k;
  }
  EXPECT_EQ(filter.stats().reinitialisations, 0u);
  EXPECT_EQ(filter.stats().gated, 12u);
  // One that agrees with the filter is fused as before.
  const PoseEstimate back = filter.update(measurement(1.0, 1.0, 0.0), 42 * kFrameNs);
  ASSERT_TRUE(back.valid);
  EXPECT_NEAR(back.pose.x_m, 1.0, 0.005);
}

// A robot standing still, then moving at 0.75 m/s from one frame to the
// next (a step no drive makes, or a push): the measurements are gated, and
// once five in a row agree the filter goes on from their own filter, with
// their motion (a restart on the last one alone had none), and nothing is
// gated after it.
TEST(TemporalFilter, RestartsOnAgreeingGatedMeasurementsWithTheirMotion) {
  TemporalFilter filter{gate_alone()};
  for (int k = 0; k < 30; ++k) filter.update(measurement(1.0, 1.0, 0.0, 0.0002), k * kFrameNs);
  int restart_frame = -1;
  uint64_t gated_at_restart = 0;
  for (int k = 30; k < 60; ++k) {
    const double x_m = 1.0 + 0.75 * (k - 29) * kFrameNs * 1e-9;
    const PoseEstimate out = filter.update(measurement(x_m, 1.0, 0.0, 0.0002), k * kFrameNs);
    if (out.valid) {
      EXPECT_NEAR(out.pose.x_m, x_m, 0.002) << "frame " << k;
    }
    if (restart_frame < 0 && filter.stats().reinitialisations == 1) {
      restart_frame = k;
      gated_at_restart = filter.stats().gated;
      EXPECT_NEAR(filter.state().x[3], 0.75, 0.02) << "the restart's velocity, m/s";
    }
  }
  ASSERT_GE(restart_frame, 0) << "never restarted";
  EXPECT_EQ(filter.stats().reinitialisations, 1u);
  EXPECT_EQ(filter.stats().gated, gated_at_restart) << "gated again after the restart";
}

TEST(TemporalFilter, PredictsThroughMissingFramesThenTimesOut) {
  FilterParams params = gate_alone();  // the timeout alone
  params.predict_timeout_ms = 200.0;
  TemporalFilter filter{params};
  for (int k = 0; k < 60; ++k) {
    const double t = k * kFrameNs * 1e-9;
    filter.update(measurement(1.0 + 0.3 * t, 1.0, 0.0), k * kFrameNs);
  }
  const double t_last = 59 * kFrameNs * 1e-9;
  // 100 ms without a pose: still valid, extrapolated along the motion.
  const int64_t gap_ns = 59 * kFrameNs + 100'000'000;
  PoseEstimate out = filter.update(PoseEstimate{}, gap_ns);
  ASSERT_TRUE(out.valid);
  EXPECT_NEAR(out.pose.x_m, 1.0 + 0.3 * (t_last + 0.1), 0.005);
  EXPECT_EQ(out.markers, 0);
  // Past the timeout: invalid, never a stale pose.
  out = filter.update(PoseEstimate{}, 59 * kFrameNs + 250'000'000);
  EXPECT_FALSE(out.valid);
  EXPECT_EQ(filter.stats().timeouts, 1u);
}

// Without measurements the prediction's yaw sd grows fast (the yaw jerk
// noise is sized for sudden turns): it is reported while SPEC §6's gross
// error (5°, 0.25 grid units) lies beyond two of its sds, then withheld,
// while the state carries on and fuses the next measurement without a
// restart. Measurements as positioning gives them (0.2 mm, 0.001 rad).
TEST(TemporalFilter, APredictionIsWithheldOnceAGrossErrorIsWithinTwoSds) {
  const FilterParams params;
  TemporalFilter filter{params};
  const double turn_radps = 1.0;
  auto yaw_at = [&](int k) { return turn_radps * k * kFrameNs * 1e-9; };
  auto measured = [&](int k) { return measurement(1.0, 1.0, yaw_at(k), 0.0002, 0.001); };
  for (int k = 0; k < 60; ++k) filter.update(measured(k), k * kFrameNs);
  const PoseEstimate one = filter.update(PoseEstimate{}, 60 * kFrameNs);
  ASSERT_TRUE(one.valid) << "one frame on: yaw sd " << std::sqrt(one.covariance[8]);
  EXPECT_LE(std::sqrt(one.covariance[8]), params.coast_max_yaw_sd_rad);
  EXPECT_LE(std::sqrt(one.covariance[0]), params.coast_max_sd_m);
  EXPECT_NEAR(one.pose.yaw_rad, yaw_at(60), 0.01);
  int withheld_from = -1;
  for (int k = 61; k < 66; ++k) {
    const PoseEstimate out = filter.update(PoseEstimate{}, k * kFrameNs);
    if (!out.valid && withheld_from < 0) withheld_from = k;
    if (withheld_from >= 0) {
      EXPECT_FALSE(out.valid) << "once withheld, withheld: frame " << k;
    }
  }
  ASSERT_GE(withheld_from, 61) << "withheld within 6 frames of coasting";
  EXPECT_EQ(filter.stats().predictions, 6u);
  EXPECT_EQ(filter.stats().too_uncertain, static_cast<uint64_t>(66 - withheld_from));
  EXPECT_EQ(filter.stats().timeouts, 0u);
  const PoseEstimate back = filter.update(measured(66), 66 * kFrameNs);
  ASSERT_TRUE(back.valid);
  EXPECT_NEAR(back.pose.yaw_rad, yaw_at(66), 0.002);
  EXPECT_EQ(filter.stats().reinitialisations, 0u) << "fused, not restarted";
  EXPECT_EQ(filter.stats().updates, 61u);
}

TEST(TemporalFilter, ResetForgetsTheTrack) {
  TemporalFilter filter{FilterParams{}};
  filter.update(measurement(1.0, 1.0, 0.0), 0);
  filter.reset();
  EXPECT_FALSE(filter.update(PoseEstimate{}, kFrameNs).valid);
  const PoseEstimate out = filter.update(measurement(4.0, 1.0, 0.0), 2 * kFrameNs);
  EXPECT_DOUBLE_EQ(out.pose.x_m, 4.0);
}

TEST(TemporalFilter, CovarianceShrinksAsMeasurementsAccumulate) {
  TemporalFilter filter{FilterParams{}};
  const PoseEstimate first = filter.update(measurement(1.0, 1.0, 0.0, 0.01), 0);
  PoseEstimate out;
  for (int k = 1; k < 20; ++k) out = filter.update(measurement(1.0, 1.0, 0.0, 0.01), k * kFrameNs);
  EXPECT_LT(out.covariance[0], first.covariance[0]);
}

// SPEC §4 allows equal stamps. A robot driving 1 m/s whose frames all carry
// one stamp (or stamps 1 ns apart) moves 33 mm between frames the filter
// cannot tell apart in time: each pose must stay within 3 of its own
// reported sd of the truth, never a smoothed pose far behind.
void expect_honest_on_stamps(int64_t stamp_step_ns) {
  TemporalFilter filter{FilterParams{}};
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.0005);
  for (int k = 0; k < 60; ++k) {
    const double truth_x_m = 1.0 + 1.0 * k * 0.0333;
    const PoseEstimate out = filter.update(
        measurement(truth_x_m + noise(rng), 1.0 + noise(rng), 0.0, 0.0005), k * stamp_step_ns);
    ASSERT_TRUE(out.valid) << "frame " << k;
    const double sd_m = std::sqrt(out.covariance[0]);
    EXPECT_LT(std::abs(out.pose.x_m - truth_x_m), 3.0 * sd_m + 1e-4) << "frame " << k;
    EXPECT_LT(sd_m, 0.001) << "frame " << k;
  }
  EXPECT_EQ(filter.stats().close_restarts, 59u);
  EXPECT_EQ(filter.stats().gated, 0u);
}

TEST(TemporalFilter, FramesWithEqualStampsRestartOnTheirOwnPose) { expect_honest_on_stamps(0); }

TEST(TemporalFilter, FramesOneNanosecondApartRestartOnTheirOwnPose) { expect_honest_on_stamps(1); }

TEST(TemporalFilter, FramesAMillisecondApartAreFused) {
  TemporalFilter filter{FilterParams{}};
  for (int k = 0; k < 10; ++k) filter.update(measurement(1.0, 1.0, 0.0), k * 1'000'000);
  EXPECT_EQ(filter.stats().close_restarts, 0u);
  EXPECT_EQ(filter.stats().updates, 10u);
}

}  // namespace
}  // namespace ceilpose
