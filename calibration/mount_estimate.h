#pragma once
// Where the camera sits on the robot (SPEC §10 `calibrate mount`), from the
// camera's own poses while the robot turns in place and drives straight
// forward: turning in place, the camera runs on a circle around the robot's
// origin (its radius and phase give the offset); driving straight, it moves
// along the robot's heading (the angle between that and the camera's yaw is
// the mounting yaw).
#include <vector>

#include "core/result.h"

namespace ceilpose {

// One frame's camera pose in `map` (the optical centre's x, y and the
// camera's yaw, i.e. localized with a zero mount).
struct CameraSample {
  double t_s = 0.0;
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

struct MountEstimate {
  double offset_forward_m = 0.0, offset_left_m = 0.0, yaw_rad = 0.0;
  double sigma_forward_m = 0.0, sigma_left_m = 0.0, sigma_yaw_rad = 0.0;
  double turned_rad = 0.0;  // total turning in place used
  double driven_m = 0.0;    // total straight drive used
  int turn_segments = 0, straight_segments = 0;
  double circle_rms_m = 0.0;  // how well the turning camera fits its circles
  double line_rms_m = 0.0;    // how well the driving camera fits its lines
};

// Refuses, saying what is missing, without at least 360° of turning in
// place and 1 m of straight forward drive in total (SPEC §10).
Result<MountEstimate> estimate_mount(const std::vector<CameraSample>& samples);

}  // namespace ceilpose
