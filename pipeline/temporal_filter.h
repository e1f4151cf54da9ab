#pragma once
// Temporal filter of the daemon: a Kalman filter on (x, y, yaw) with the
// constant-acceleration model of core/motion_model.h, yaw wrapping, gating of
// jumps, counted re-initialisation and prediction through missing frames up
// to a timeout. Its state (pose, rates, accelerations and their covariance)
// is what the pose client extrapolates from.
#include <array>
#include <cstdint>

#include "core/motion_model.h"
#include "pipeline/pose_estimate.h"
#include "pipeline/positioning_params.h"

namespace ceilpose {

struct FilterStats {
  uint64_t updates = 0;            // measurements fused
  uint64_t gated = 0;              // measurements refused as jumps (no pose published)
  uint64_t reinitialisations = 0;  // re-starts after reinit_after_gated gated in a row
  uint64_t predictions = 0;        // outputs predicted without a measurement
  uint64_t too_uncertain = 0;      // of those, withheld as past coast_max_sd_m / _yaw_sd_rad
  uint64_t timeouts = 0;           // times the filter gave up after predict_timeout_ms
  uint64_t close_restarts = 0;     // re-starts on a frame within min_frame_interval_ms
};

// Whether the difference y between two poses (x_m, y_m, yaw_rad), with
// s_inv the inverse of its covariance, is a jump: beyond the chi-square gate
// (FilterParams::gate_chi2) and not within the small-difference allowance
// (gate_min_m, gate_min_rad). The filter refuses such a measurement; the
// localizer's scheduled check drops a track whose whole sweep differs so.
bool is_jump(const FilterParams& params, const std::array<double, 3>& y,
             const std::array<double, 9>& s_inv);

// Not thread-safe: one instance, called from the pipeline thread in frame
// order. update() allocates nothing and throws nothing.
class TemporalFilter {
 public:
  explicit TemporalFilter(const FilterParams& params);

  // Fuses one frame's estimate (valid or not) of the frame taken at
  // `timestamp_ns` (monotonic), at the instant the estimate refers to
  // (timestamp_ns + its time_offset_s), and returns the filtered pose at
  // timestamp_ns; invalid until a first valid measurement and again once
  // predict_timeout_ms passes without one; a prediction without a fused
  // measurement is invalid (the state carries on) once its sd passes
  // coast_max_sd_m or coast_max_yaw_sd_rad; a frame whose measurement is a
  // jump (is_jump) is invalid too, until reinit_after_gated in a row that
  // agree with each other (each within the gate of a filter of their own)
  // restart the filter on theirs. An instant earlier than the
  // previous one is treated as the same instant. A valid measurement of a
  // frame stamped within min_frame_interval_ms of the last one fused (or
  // earlier) restarts the filter on itself.
  PoseEstimate update(const PoseEstimate& measurement, int64_t timestamp_ns);
  void reset();

  const FilterStats& stats() const { return stats_; }
  // The state at the last update's instant; meaningful while initialised().
  bool initialised() const { return initialised_; }
  const MotionState& state() const { return state_; }
  int64_t state_time_ns() const { return last_ns_; }
  JerkDensity jerk_density() const;
  // The state as consumers carry it to another instant (within
  // predict_horizon_ms); not valid before initialisation.
  MotionEstimate motion() const;

 private:
  static constexpr int kN = kMotionStates;
  std::array<double, 9> floored_covariance(const PoseEstimate& m) const;
  // The state a first measurement gives: its pose and covariance, motion
  // unknown (the init sigmas).
  MotionState initial_state(const PoseEstimate& measurement) const;
  // Starts (again) from `state` at state_ns, `measurement` the last fused.
  void initialise(const MotionState& state, int64_t state_ns, const PoseEstimate& measurement,
                  int64_t timestamp_ns);
  int follow_gated(const PoseEstimate& measurement, int64_t timestamp_ns);
  // The Kalman steps, on the filter's state or the gated measurements'.
  // predict moves a state at *state_ns on to to_ns (and *state_ns with it).
  void predict(MotionState* state, int64_t* state_ns, int64_t to_ns) const;
  bool innovation(const MotionState& state, const PoseEstimate& m, std::array<double, 3>* y,
                  std::array<double, 9>* s_inv) const;
  // The prediction to frame_ns without a measurement, invalid past the
  // coasting bounds.
  PoseEstimate coast(int64_t frame_ns);
  void correct(MotionState* state, const std::array<double, 3>& y,
               const std::array<double, 9>& s_inv) const;
  PoseEstimate output(const PoseEstimate* used, int64_t timestamp_ns) const;

  FilterParams params_;
  FilterStats stats_;
  bool initialised_ = false;
  MotionState state_;
  int64_t last_ns_ = 0;              // time the state refers to
  int64_t last_measurement_ns_ = 0;  // last fused (or initialising) measurement
  int64_t last_frame_ns_ = 0;        // the frame stamp of that measurement
  int consecutive_gated_ = 0;        // gated in a row that agree with each other
  MotionState candidate_;            // their filter (follow_gated)
  int64_t candidate_ns_ = 0;
  PositioningMode last_mode_ = PositioningMode::kAuto;
};

}  // namespace ceilpose
