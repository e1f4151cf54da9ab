#include "ipc/shm/pose_record.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/finite.h"

namespace ceilpose {

const char* to_string(WriterState state) {
  switch (state) {
    case WriterState::kStarting:
      return "starting";
    case WriterState::kRunning:
      return "running";
    case WriterState::kStopped:
      return "stopped";
  }
  return "unknown";
}

const char* pose_mode_name(uint8_t mode) {
  // The names are string_views over literals: NUL-terminated.
  return mode < kPositioningModes.size() ? to_string(static_cast<PositioningMode>(mode)).data()
                                         : "unknown";
}

bool pose_numbers_finite(const PoseRecord& p) {
  const double scalars[] = {p.x_m,     p.y_m,     p.yaw_rad,
                            p.vx_mps,  p.vy_mps,  p.yaw_rate_radps,
                            p.ax_mps2, p.ay_mps2, p.yaw_accel_radps2};
  return all_finite(scalars) && all_finite(p.covariance) && all_finite(p.state_covariance) &&
         all_finite(p.jerk_density);
}

void make_publishable(PoseRecord* p) {
  if (pose_numbers_finite(*p)) return;
  p->flags &= ~(kPoseValid | kPoseMotion | kPoseCoasting);
  p->x_m = p->y_m = p->yaw_rad = 0.0;
  std::fill(std::begin(p->covariance), std::end(p->covariance), 0.0);
  set_pose_motion(p, MotionEstimate{});
}

void set_pose_motion(PoseRecord* p, const MotionEstimate& m) {
  if (!m.valid) {
    p->flags &= ~kPoseMotion;
    p->vx_mps = p->vy_mps = p->yaw_rate_radps = 0.0;
    p->ax_mps2 = p->ay_mps2 = p->yaw_accel_radps2 = 0.0;
    std::fill(std::begin(p->state_covariance), std::end(p->state_covariance), 0.0);
    std::fill(std::begin(p->jerk_density), std::end(p->jerk_density), 0.0);
    p->predict_horizon_ms = 0;
    return;
  }
  p->flags |= kPoseMotion;
  p->vx_mps = m.state.x[3];
  p->vy_mps = m.state.x[4];
  p->yaw_rate_radps = m.state.x[5];
  p->ax_mps2 = m.state.x[6];
  p->ay_mps2 = m.state.x[7];
  p->yaw_accel_radps2 = m.state.x[8];
  std::copy(m.state.p.begin(), m.state.p.end(), p->state_covariance);
  std::copy(m.jerk.begin(), m.jerk.end(), p->jerk_density);
  p->predict_horizon_ms = static_cast<uint32_t>(std::clamp(m.horizon_ms, 0.0, 4.0e9));
}

MotionEstimate pose_motion(const PoseRecord& p) {
  MotionEstimate m;
  m.valid = (p.flags & kPoseMotion) != 0 && pose_is_valid(p);
  m.time_ns = p.capture_mono_ns;
  m.state.x = {p.x_m,     p.y_m,     p.yaw_rad,         p.vx_mps, p.vy_mps, p.yaw_rate_radps,
               p.ax_mps2, p.ay_mps2, p.yaw_accel_radps2};
  std::copy(std::begin(p.state_covariance), std::end(p.state_covariance), m.state.p.begin());
  std::copy(std::begin(p.jerk_density), std::end(p.jerk_density), m.jerk.begin());
  m.horizon_ms = p.predict_horizon_ms;
  return m;
}

PredictResult predict_pose_in_place(PoseRecord* pose, int64_t t_mono_ns) {
  PoseRecord& p = *pose;
  if ((p.flags & kPoseMotion) == 0 || !pose_is_valid(p)) return PredictResult::kNoMotion;
  if (!within_horizon(p.capture_mono_ns, p.predict_horizon_ms, t_mono_ns))
    return PredictResult::kBeyondHorizon;
  // motion_at on the record's own arrays (no MotionEstimate copied in and
  // out: a controller predicts every robot of the fleet each cycle).
  const double x[kMotionStates] = {p.x_m,     p.y_m,     p.yaw_rad,
                                   p.vx_mps,  p.vy_mps,  p.yaw_rate_radps,
                                   p.ax_mps2, p.ay_mps2, p.yaw_accel_radps2};
  double x_out[kMotionStates];
  double* p_out = p.state_covariance;  // in place: propagate_motion allows it
  const JerkDensity jerk{p.jerk_density[0], p.jerk_density[1], p.jerk_density[2]};
  propagate_motion(x, p.state_covariance, static_cast<double>(t_mono_ns - p.capture_mono_ns) * 1e-9,
                   jerk, x_out, p_out, 2);
  p.x_m = x_out[0];
  p.y_m = x_out[1];
  p.yaw_rad = wrap_angle_rad(x_out[2]);
  p.vx_mps = x_out[3];
  p.vy_mps = x_out[4];
  p.yaw_rate_radps = x_out[5];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) p.covariance[r * 3 + c] = p_out[r * kMotionStates + c];
  return PredictResult::kOk;
}

PredictResult predict_pose(const PoseRecord& pose, int64_t t_mono_ns, PoseRecord* out) {
  *out = pose;
  const PredictResult r = predict_pose_in_place(out, t_mono_ns);
  if (r != PredictResult::kOk) *out = pose;
  return r;
}

void set_status_source(StatusRecord* status, const char* text) {
  std::strncpy(status->source, text, sizeof(status->source) - 1);
  status->source[sizeof(status->source) - 1] = '\0';
}

}  // namespace ceilpose
