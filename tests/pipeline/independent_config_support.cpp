#include "tests/pipeline/independent_config_support.h"

namespace ceilpose::testing::xcheck {

PipelineConfig config_for(const XCamera& camera, const XMount& mount) {
  PipelineConfig config;
  config.intrinsics.width = camera.width;
  config.intrinsics.height = camera.height;
  config.intrinsics.fx = camera.fx;
  config.intrinsics.fy = camera.fy;
  config.intrinsics.cx = camera.cx;
  config.intrinsics.cy = camera.cy;
  config.intrinsics.distortion = camera.distortion;
  config.mount.lens_height_m = mount.lens_height_m;
  config.mount.offset_forward_m = mount.offset_forward_m;
  config.mount.offset_left_m = mount.offset_left_m;
  config.mount.yaw_rad = mount.yaw_rad;
  return config;
}

}  // namespace ceilpose::testing::xcheck
