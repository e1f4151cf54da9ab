/* Prints every field of ceilpose_pose as "name offset size", then "sizeof
 * N", then the same for the fleet records as "fleet_robot.name ..." and
 * "fleet_info.name ...": what the C compiler made of the header, for the
 * Python module's ctypes layout to be compared with, field by field
 * (test_client.py). */
#include <stdio.h>

#include "ceilpose/pose_client.h"

#define FIELD(f) printf(#f " %zu %zu\n", offsetof(ceilpose_pose, f), sizeof(((ceilpose_pose*)0)->f))
#define OF(type, prefix, f) \
  printf(prefix "." #f " %zu %zu\n", offsetof(type, f), sizeof(((type*)0)->f))
#define ROBOT(f) OF(ceilpose_fleet_robot, "fleet_robot", f)
#define INFO(f) OF(ceilpose_fleet_info, "fleet_info", f)

int main(void) {
  FIELD(seq);
  FIELD(capture_mono_ns);
  FIELD(capture_real_ns);
  FIELD(publish_mono_ns);
  FIELD(publish_real_ns);
  FIELD(x_m);
  FIELD(y_m);
  FIELD(yaw_rad);
  FIELD(covariance);
  FIELD(flags);
  FIELD(mode);
  FIELD(refusal);
  FIELD(markers);
  FIELD(vx_mps);
  FIELD(vy_mps);
  FIELD(yaw_rate_radps);
  FIELD(ax_mps2);
  FIELD(ay_mps2);
  FIELD(yaw_accel_radps2);
  FIELD(state_covariance);
  FIELD(jerk_density);
  FIELD(predict_horizon_ms);
  FIELD(reserved0);
  printf("sizeof %zu\n", sizeof(ceilpose_pose));
  ROBOT(robot);
  ROBOT(pose);
  ROBOT(received_mono_ns);
  ROBOT(latency_ns);
  ROBOT(samples);
  ROBOT(fleet_flags);
  ROBOT(lost);
  printf("fleet_robot.sizeof %zu\n", sizeof(ceilpose_fleet_robot));
  INFO(pid);
  INFO(state);
  INFO(generation);
  INFO(heartbeat_mono_ns);
  INFO(capacity);
  INFO(robots);
  INFO(stale_after_ms);
  INFO(reserved0);
  INFO(accepted);
  INFO(refused_full);
  INFO(refused_future);
  INFO(refused_past);
  INFO(refused_invalid);
  INFO(refused_duplicate);
  INFO(removed);
  printf("fleet_info.sizeof %zu\n", sizeof(ceilpose_fleet_info));
  return 0;
}
