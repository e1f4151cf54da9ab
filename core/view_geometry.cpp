#include "core/view_geometry.h"

#include <cmath>

namespace ceilpose {

ViewGeometry::ViewGeometry(const CameraIntrinsics& intrinsics, const CameraMount& mount,
                           const CeilingLayout& layout, const CeilingMap* map)
    : intrinsics_(intrinsics),
      mount_(mount),
      layout_(layout),
      map_(map != nullptr ? *map : CeilingMap(layout)),
      depth_m_(layout.height_m - mount.lens_height_m),
      tilt_(tilt_rotation(mount.tilt_x_rad, mount.tilt_y_rad)) {}

void ViewGeometry::level_normalized(double u_px, double v_px, double* x_n, double* y_n) const {
  double x = 0.0, y = 0.0;
  undistort_pixel(intrinsics_, u_px, v_px, &x, &y);
  // The camera axes in the world are Level(yaw)·tilt (camera_model.h), so
  // tilt·ray is the ray in the level camera's frame.
  const Vec3 r = mat_vec(tilt_, {x, y, 1.0});
  *x_n = r[0] / r[2];
  *y_n = r[1] / r[2];
}

void ViewGeometry::ceiling_offset(double cam_yaw_rad, double x_n, double y_n, double* dx_m,
                                  double* dy_m) const {
  level_to_world(std::cos(cam_yaw_rad), std::sin(cam_yaw_rad), depth_m_ * x_n, depth_m_ * y_n, dx_m,
                 dy_m);
}

Pose2D ViewGeometry::robot_from_camera(double cam_x_m, double cam_y_m, double cam_yaw_rad) const {
  const double yaw = wrap_angle_rad(cam_yaw_rad - mount_.yaw_rad);
  double ox_m = 0.0, oy_m = 0.0;
  mount_offset_world(mount_, yaw, &ox_m, &oy_m);
  return Pose2D{cam_x_m - ox_m, cam_y_m - oy_m, yaw};
}

}  // namespace ceilpose
