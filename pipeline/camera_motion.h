#pragma once
// What the pipeline may be told of the camera's motion during a frame's
// readout (rolling shutter): the temporal filter's prediction at the frame's
// time, moved to the optical centre. The pipeline does not know where it
// came from; it only uses it when the frame cannot tell the motion itself
// (held) or as the prior of what the frame tells (lsq).
namespace ceilpose {

struct CameraMotion {
  bool valid = false;
  double vx_mps = 0.0;  // optical centre velocity, world frame
  double vy_mps = 0.0;
  double yaw_rate_radps = 0.0;
  double sigma_v_mps = 0.0;  // 1-sigma of each velocity component
  double sigma_yaw_rate_radps = 0.0;
};

}  // namespace ceilpose
