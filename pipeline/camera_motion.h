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

// How far a point of the robot moves tau_s after an instant at which it
// moves at (vx, vy) m/s while the robot turns at w rad/s: a constant twist,
// the constant-velocity model of a rigid body in the plane, whose velocity
// turns with the body (a wheeled robot's arc). To second order in tau: the
// third order is below 0.01 mm over half a 33 ms readout at 3 rad/s and
// 1.5 m/s, where the second, which a velocity constant in the world leaves
// out, is 0.6 mm.
inline void arc_displacement(double vx_mps, double vy_mps, double w_radps, double tau_s,
                             double* dx_m, double* dy_m) {
  const double turn_s = 0.5 * w_radps * tau_s * tau_s;
  *dx_m = vx_mps * tau_s - vy_mps * turn_s;
  *dy_m = vy_mps * tau_s + vx_mps * turn_s;
}

}  // namespace ceilpose
