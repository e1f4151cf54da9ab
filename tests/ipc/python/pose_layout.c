/* Prints every field of ceilpose_pose as "name offset size", then "sizeof
 * N": what the C compiler made of the header, for the Python module's
 * ctypes layout to be compared with, field by field (test_client.py). */
#include <stdio.h>

#include "ceilpose/pose_client.h"

#define FIELD(f) printf(#f " %zu %zu\n", offsetof(ceilpose_pose, f), sizeof(((ceilpose_pose*)0)->f))

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
  return 0;
}
