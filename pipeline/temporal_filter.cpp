#include "pipeline/temporal_filter.h"

#include <algorithm>
#include <cmath>

#include "core/small_matrix.h"

namespace ceilpose {
TemporalFilter::TemporalFilter(const FilterParams& params) : params_(params) {}

void TemporalFilter::reset() {
  initialised_ = false;
  consecutive_gated_ = 0;
}

JerkDensity TemporalFilter::jerk_density() const {
  const double j = params_.jerk_sigma_mps3, yj = params_.yaw_jerk_sigma_radps3;
  return {j * j, j * j, yj * yj};
}

MotionEstimate TemporalFilter::motion() const {
  if (!initialised_) return {};
  return MotionEstimate{true, last_ns_, state_, jerk_density(), params_.predict_horizon_ms};
}

// The measurement's covariance with the configured floors: a solver's
// sigma of micrometres must not make the filter trust it beyond what the
// pose is really worth.
std::array<double, 9> TemporalFilter::floored_covariance(const PoseEstimate& m) const {
  std::array<double, 9> r = m.covariance;
  const double floor_m2 = params_.meas_sigma_floor_m * params_.meas_sigma_floor_m;
  const double floor_rad2 = params_.meas_sigma_floor_yaw_rad * params_.meas_sigma_floor_yaw_rad;
  r[0] = std::max(r[0], floor_m2);
  r[4] = std::max(r[4], floor_m2);
  r[8] = std::max(r[8], floor_rad2);
  return r;
}

MotionState TemporalFilter::initial_state(const PoseEstimate& m) const {
  MotionState state;
  state.x.fill(0.0);
  state.x[0] = m.pose.x_m;
  state.x[1] = m.pose.y_m;
  state.x[2] = m.pose.yaw_rad;
  std::array<double, kN* kN>& p = state.p;
  p.fill(0.0);
  const std::array<double, 9> r = floored_covariance(m);
  for (int row = 0; row < 3; ++row)
    for (int c = 0; c < 3; ++c) p[row * kN + c] = r[row * 3 + c];
  const double sigma[kN] = {0.0,
                            0.0,
                            0.0,
                            params_.init_velocity_sigma_mps,
                            params_.init_velocity_sigma_mps,
                            params_.init_yaw_rate_sigma_radps,
                            params_.init_accel_sigma_mps2,
                            params_.init_accel_sigma_mps2,
                            params_.init_yaw_accel_sigma_radps2};
  for (int i = 3; i < kN; ++i) p[i * kN + i] = sigma[i] * sigma[i];
  return state;
}

void TemporalFilter::initialise(const MotionState& state, int64_t state_ns, const PoseEstimate& m,
                                int64_t timestamp_ns) {
  state_ = state;
  initialised_ = true;
  last_ns_ = state_ns;
  last_measurement_ns_ = timestamp_ns;
  consecutive_gated_ = 0;
  last_mode_ = m.mode;
}

// An instant earlier than the state's is treated as the same instant.
void TemporalFilter::predict(MotionState* state, int64_t* state_ns, int64_t to_ns) const {
  if (to_ns <= *state_ns) return;
  const MotionState before = *state;
  propagate_motion(before, static_cast<double>(to_ns - *state_ns) * 1e-9, jerk_density(), state);
  state->x[2] = wrap_angle_rad(state->x[2]);
  *state_ns = to_ns;
}

PoseEstimate TemporalFilter::output(const PoseEstimate* used, int64_t timestamp_ns) const {
  // The state may be a rolling shutter's few milliseconds off the frame.
  MotionState at = state_;
  if (timestamp_ns != last_ns_)
    propagate_motion(state_, static_cast<double>(timestamp_ns - last_ns_) * 1e-9, jerk_density(),
                     &at, 1);
  PoseEstimate out;
  out.valid = true;
  out.pose = {at.x[0], at.x[1], wrap_angle_rad(at.x[2])};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out.covariance[r * 3 + c] = at.p[r * kN + c];
  out.mode = used != nullptr ? used->mode : last_mode_;
  out.markers = used != nullptr ? used->markers : 0;
  out.rms_residual_px = used != nullptr ? used->rms_residual_px : 0.0;
  return out;
}

// Innovation y = z - H x (yaw wrapped) and the inverse of its covariance
// S = P33 + R, R being the measurement's covariance with the floors applied.
// False when S is singular.
bool TemporalFilter::innovation(const MotionState& state, const PoseEstimate& m,
                                std::array<double, 3>* y, std::array<double, 9>* s_inv) const {
  *y = {m.pose.x_m - state.x[0], m.pose.y_m - state.x[1],
        wrap_angle_rad(m.pose.yaw_rad - state.x[2])};
  const std::array<double, 9> r = floored_covariance(m);
  std::array<double, 9> s{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s[i * 3 + j] = state.p[i * kN + j] + r[i * 3 + j];
  return invert3(s, s_inv);
}

bool is_jump(const FilterParams& params, const std::array<double, 3>& y,
             const std::array<double, 9>& s_inv) {
  const double d2 = quadratic_form3(s_inv, y);
  const bool small =
      std::hypot(y[0], y[1]) <= params.gate_min_m && std::abs(y[2]) <= params.gate_min_rad;
  return d2 > params.gate_chi2 && !small;
}

// K = P H^T S^-1 (9x3); x += K y; P -= K H P, kept symmetric.
void TemporalFilter::correct(MotionState* state, const std::array<double, 3>& y,
                             const std::array<double, 9>& s_inv) const {
  MotionState& st = *state;
  std::array<double, kN * 3> k{};
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < 3; ++j) {
      double sum = 0.0;
      for (int l = 0; l < 3; ++l) sum += st.p[i * kN + l] * s_inv[l * 3 + j];
      k[i * 3 + j] = sum;
    }
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < 3; ++j) st.x[i] += k[i * 3 + j] * y[j];
  st.x[2] = wrap_angle_rad(st.x[2]);
  std::array<double, kN* kN> p = st.p;
  for (int i = 0; i < kN; ++i)
    for (int c = 0; c < kN; ++c) {
      double sum = 0.0;
      for (int j = 0; j < 3; ++j) sum += k[i * 3 + j] * st.p[j * kN + c];
      p[i * kN + c] -= sum;
    }
  for (int i = 0; i < kN; ++i)  // against round-off
    for (int c = i + 1; c < kN; ++c)
      p[i * kN + c] = p[c * kN + i] = 0.5 * (p[i * kN + c] + p[c * kN + i]);
  st.p = p;
}

PoseEstimate TemporalFilter::coast(int64_t frame_ns) {
  ++stats_.predictions;
  PoseEstimate out = output(nullptr, frame_ns);
  const double var_m2 = std::max(out.covariance[0], out.covariance[4]);
  const double max_m = params_.coast_max_sd_m, max_rad = params_.coast_max_yaw_sd_rad;
  if (!(var_m2 <= max_m * max_m) || !(out.covariance[8] <= max_rad * max_rad)) {
    ++stats_.too_uncertain;
    return PoseEstimate{};
  }
  return out;
}

// The gated measurements in a row, in a filter of their own (candidate_):
// each one within that filter's gate is fused into it and counted; one
// beyond it (they disagree among themselves: a wrong decode among them, or
// the robot moved again) starts it afresh. Returns how many in a row agree.
int TemporalFilter::follow_gated(const PoseEstimate& m, int64_t timestamp_ns) {
  if (consecutive_gated_ > 0) {
    predict(&candidate_, &candidate_ns_, timestamp_ns);
    std::array<double, 3> y{};
    std::array<double, 9> s_inv{};
    if (innovation(candidate_, m, &y, &s_inv) && !is_jump(params_, y, s_inv)) {
      correct(&candidate_, y, s_inv);
      return ++consecutive_gated_;
    }
  }
  candidate_ = initial_state(m);
  candidate_ns_ = timestamp_ns;
  return consecutive_gated_ = 1;
}

PoseEstimate TemporalFilter::update(const PoseEstimate& m, int64_t frame_ns) {
  const int64_t timestamp_ns =
      m.valid ? frame_ns + static_cast<int64_t>(std::llround(m.time_offset_s * 1e9)) : frame_ns;
  const double timeout_ns = params_.predict_timeout_ms * 1e6;
  if (initialised_ && static_cast<double>(timestamp_ns - last_measurement_ns_) > timeout_ns) {
    initialised_ = false;
    ++stats_.timeouts;
  }
  const bool too_close =
      initialised_ && m.valid &&
      static_cast<double>(frame_ns - last_frame_ns_) < params_.min_frame_interval_ms * 1e6;
  if (!initialised_ || too_close) {
    if (!m.valid) return PoseEstimate{};
    if (too_close) ++stats_.close_restarts;
    initialise(initial_state(m), timestamp_ns, m, timestamp_ns);
    last_frame_ns_ = frame_ns;
    ++stats_.updates;
    return output(&m, frame_ns);
  }
  predict(&state_, &last_ns_, timestamp_ns);
  std::array<double, 3> y{};
  std::array<double, 9> s_inv{};
  if (!m.valid || !innovation(state_, m, &y, &s_inv)) {
    return coast(frame_ns);
  }
  if (is_jump(params_, y, s_inv)) {
    ++stats_.gated;
    if (follow_gated(m, timestamp_ns) >= params_.reinit_after_gated) {
      // The measurements have agreed with each other, not with us, for long
      // enough: the robot was moved or the filter diverged. The filter goes
      // on from theirs, which has their motion too.
      ++stats_.reinitialisations;
      initialise(candidate_, candidate_ns_, m, timestamp_ns);
      last_frame_ns_ = frame_ns;
      return output(&m, frame_ns);
    }
    // The measurement and the prediction disagree beyond the gate: one of
    // them is grossly wrong and nothing here says which (a decode gone
    // wrong, or a robot picked up and set down, or moving faster than the
    // model allows), so neither is published (docs/decisions.md).
    return PoseEstimate{};
  }
  correct(&state_, y, s_inv);
  consecutive_gated_ = 0;
  last_measurement_ns_ = timestamp_ns;
  last_frame_ns_ = frame_ns;
  last_mode_ = m.mode;
  ++stats_.updates;
  return output(&m, frame_ns);
}

}  // namespace ceilpose
