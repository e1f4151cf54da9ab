#include "ipc/shm/pose_record.h"

#include <algorithm>
#include <cmath>
#include <cstring>

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

PredictResult predict_pose(const PoseRecord& pose, int64_t t_mono_ns, PoseRecord* out) {
  *out = pose;
  MotionState ahead;
  switch (predict_motion(pose_motion(pose), t_mono_ns, &ahead)) {
    case PredictOutcome::kNoMotion:
      return PredictResult::kNoMotion;
    case PredictOutcome::kBeyondHorizon:
      return PredictResult::kBeyondHorizon;
    case PredictOutcome::kOk:
      break;
  }
  out->x_m = ahead.x[0];
  out->y_m = ahead.x[1];
  out->yaw_rad = ahead.x[2];
  out->vx_mps = ahead.x[3];
  out->vy_mps = ahead.x[4];
  out->yaw_rate_radps = ahead.x[5];
  std::copy(ahead.p.begin(), ahead.p.end(), out->state_covariance);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      out->covariance[r * 3 + c] = out->state_covariance[r * kMotionStates + c];
  return PredictResult::kOk;
}

void set_status_source(StatusRecord* status, const char* text) {
  std::strncpy(status->source, text, sizeof(status->source) - 1);
  status->source[sizeof(status->source) - 1] = '\0';
}

}  // namespace ceilpose
