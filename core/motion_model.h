#pragma once
// The robot's motion model, shared by the daemon's temporal filter and the
// pose client's prediction so that "where am I at t" has one answer: constant
// acceleration on x, y and yaw, driven by white jerk.
//
// State order (index = order * 3 + axis): x_m, y_m, yaw_rad, vx_mps, vy_mps,
// yaw_rate_radps, ax_mps2, ay_mps2, yaw_accel_radps2; world frame. Chosen over
// constant velocity because a robot on a curve accelerates all the time
// (v²/r = 2.2 m/s² at 1.5 m/s on a 1 m radius): a constant-velocity model
// either lags or predicts 66 ms ahead 5 mm off (docs/latency.md has the
// figures). Allocation-free, header-only: the C client links no pipeline.
#include <array>
#include <cmath>
#include <cstdint>

#include "core/pose.h"

namespace ceilpose {

inline constexpr int kMotionAxes = 3;    // x, y, yaw
inline constexpr int kMotionOrders = 3;  // value, rate, acceleration
inline constexpr int kMotionStates = kMotionAxes * kMotionOrders;

struct MotionState {
  std::array<double, kMotionStates> x{};
  std::array<double, kMotionStates * kMotionStates> p{};  // covariance, row-major
};

// Process noise: the jerk's power spectral density per axis, (m/s³)²·s for
// x and y, (rad/s³)²·s for yaw. `filter.jerk_sigma_mps3` is its square root.
using JerkDensity = std::array<double, kMotionAxes>;

// Propagates state x / covariance p (row-major kMotionStates²) by dt_s
// seconds (either sign; the added noise grows with |dt|) into x_out / p_out.
// x_out must not overlap x; p_out may be p itself (P Fᵀ is taken whole into
// a local before anything is written), which spares a controller a copy. Only the first `orders`
// derivative orders are written (1: pose, 2: pose and rates, 3: all); the rest of the outputs is
// left as it was. The yaw is not wrapped. On raw arrays so that the pose client carries a
// shared-memory record without copying it.
inline void propagate_motion(const double* x, const double* p, double dt_s, const JerkDensity& jerk,
                             double* x_out, double* p_out, int orders = kMotionOrders) {
  constexpr int A = kMotionAxes;
  constexpr int N = kMotionStates;
  // Row k of F maps order k from orders k..2 with c = [1, dt, dt²/2].
  const double c[kMotionOrders] = {1.0, dt_s, 0.5 * dt_s * dt_s};
  for (int i = 0; i < orders; ++i)
    for (int a = 0; a < A; ++a) {
      double sum = 0.0;
      for (int k = i; k < kMotionOrders; ++k) sum += c[k - i] * x[k * A + a];
      x_out[i * A + a] = sum;
    }
  // P' block (i, j) = Σ_{k≥i} c[k-i] (Σ_{l≥j} c[l-j] P block (k, l)): the
  // inner sum (P Fᵀ) once per row, then F from the left.
  double pf[N][N];
  for (int r = 0; r < N; ++r)
    for (int j = 0; j < orders; ++j)
      for (int b = 0; b < A; ++b) {
        double sum = 0.0;
        for (int l = j; l < kMotionOrders; ++l) sum += c[l - j] * p[r * N + l * A + b];
        pf[r][j * A + b] = sum;
      }
  for (int i = 0; i < orders; ++i)
    for (int a = 0; a < A; ++a)
      for (int col = 0; col < orders * A; ++col) {
        double sum = 0.0;
        for (int k = i; k < kMotionOrders; ++k) sum += c[k - i] * pf[k * A + a][col];
        p_out[(i * A + a) * N + col] = sum;
      }
  // White jerk, integrated over |dt|: q·[t⁵/20 t⁴/8 t³/6; t⁴/8 t³/3 t²/2; t³/6 t²/2 t].
  const double t = std::abs(dt_s);
  const double t2 = t * t, t3 = t2 * t;
  const double q[kMotionOrders][kMotionOrders] = {{t3 * t2 / 20.0, t2 * t2 / 8.0, t3 / 6.0},
                                                  {t2 * t2 / 8.0, t3 / 3.0, t2 / 2.0},
                                                  {t3 / 6.0, t2 / 2.0, t}};
  for (int i = 0; i < orders; ++i)
    for (int j = 0; j < orders; ++j)
      for (int a = 0; a < A; ++a) p_out[(i * A + a) * N + j * A + a] += jerk[a] * q[i][j];
}

inline void propagate_motion(const MotionState& in, double dt_s, const JerkDensity& jerk,
                             MotionState* out, int orders = kMotionOrders) {
  propagate_motion(in.x.data(), in.p.data(), dt_s, jerk, out->x.data(), out->p.data(), orders);
}

// The filter's belief at one instant, with the noise needed to carry it to
// another: what the daemon publishes with every filtered pose.
struct MotionEstimate {
  bool valid = false;
  int64_t time_ns = 0;  // CLOCK_MONOTONIC instant `state` refers to (the frame's)
  MotionState state;
  JerkDensity jerk{};
  double horizon_ms = 0.0;  // how far from time_ns a consumer may carry it
};

// Whether t_ns is within the estimate's horizon of its instant: the one
// rule for every consumer (the pose client, the filter's readout motion,
// `locate --predict-ms`). In double: an int64 difference of arbitrary
// instants cannot overflow it; NaN is never within.
inline bool within_horizon(int64_t time_ns, double horizon_ms, int64_t t_ns) {
  const double dt_ms = (static_cast<double>(t_ns) - static_cast<double>(time_ns)) * 1e-6;
  return std::abs(dt_ms) <= horizon_ms;
}
inline bool within_horizon(const MotionEstimate& m, int64_t t_ns) {
  return within_horizon(m.time_ns, m.horizon_ms, t_ns);
}

// The estimate carried to t_ns: pose (yaw wrapped) and rates with their
// covariance (orders 0 and 1 only; the accelerations stay as they were).
// No horizon check: callers that may be asked beyond it use predict_motion.
inline MotionState motion_at(const MotionEstimate& m, int64_t t_ns) {
  MotionState out = m.state;
  propagate_motion(m.state, static_cast<double>(t_ns - m.time_ns) * 1e-9, m.jerk, &out, 2);
  out.x[2] = wrap_angle_rad(out.x[2]);
  return out;
}

enum class PredictOutcome { kOk, kNoMotion, kBeyondHorizon };

// motion_at with the checks every prediction makes: an estimate without
// motion, or an instant beyond its horizon, is refused (*out untouched).
inline PredictOutcome predict_motion(const MotionEstimate& m, int64_t t_ns, MotionState* out) {
  if (!m.valid) return PredictOutcome::kNoMotion;
  if (!within_horizon(m, t_ns)) return PredictOutcome::kBeyondHorizon;
  *out = motion_at(m, t_ns);
  return PredictOutcome::kOk;
}

}  // namespace ceilpose
