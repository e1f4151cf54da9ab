#pragma once
// The view geometry every positioning mode, the survey and calibration
// share: undistorting and levelling image points, and turning a camera
// position and heading into the robot's pose (mount offset and yaw removed).
#include "core/camera_model.h"
#include "core/ceiling_layout.h"
#include "core/ceiling_map.h"
#include "core/pose.h"

namespace ceilpose {

// Constant per configuration; computed once, then read on every frame.
class ViewGeometry {
 public:
  // `map` null: the nominal grid of `layout`.
  ViewGeometry(const CameraIntrinsics& intrinsics, const CameraMount& mount,
               const CeilingLayout& layout, const CeilingMap* map);
  // Any configuration with intrinsics, mount, layout and a map pointer
  // (pipeline's PipelineConfig), without core depending on it.
  template <typename Config>
  explicit ViewGeometry(const Config& c)
      : ViewGeometry(c.intrinsics, c.mount, c.layout, c.map.get()) {}

  const CameraIntrinsics& intrinsics() const { return intrinsics_; }
  const CameraMount& mount() const { return mount_; }
  const CeilingLayout& layout() const { return layout_; }
  // The configured map, or the nominal grid when none is configured.
  const CeilingMap& map() const { return map_; }
  // Lens to ceiling distance H - h, metres.
  double depth_m() const { return depth_m_; }
  // The thesis's scale: pixels per grid unit on the ceiling, fx·g/(H−h).
  double pixels_per_grid_unit() const { return intrinsics_.fx * layout_.grid_m / depth_m_; }
  // Nominal tilt: rotation from the camera frame to the level camera frame.
  const Mat3& tilt() const { return tilt_; }

  // Pixel (as measured, distorted) to normalized coordinates of the level
  // camera: undistorted, then rotated by the nominal mount tilt, so that
  // (0, 0) is the ceiling point straight above the lens.
  void level_normalized(double u_px, double v_px, double* x_n, double* y_n) const;

  // The world offset from the optical centre of the ceiling point at level
  // normalized (x_n, y_n), for a camera of yaw cam_yaw_rad.
  void ceiling_offset(double cam_yaw_rad, double x_n, double y_n, double* dx_m, double* dy_m) const;

  // Robot pose from the optical centre's (x, y) and the camera yaw (the
  // heading of image-up on the floor).
  Pose2D robot_from_camera(double cam_x_m, double cam_y_m, double cam_yaw_rad) const;

 private:
  CameraIntrinsics intrinsics_;
  CameraMount mount_;
  CeilingLayout layout_;
  CeilingMap map_;
  double depth_m_ = 0.0;
  Mat3 tilt_{};
};

}  // namespace ceilpose
