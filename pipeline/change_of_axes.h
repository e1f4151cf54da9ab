#pragma once
// Change of Axes (thesis, one marker) and the view geometry every positioning
// mode shares: undistorting and levelling image points, and turning a camera
// position and heading into the robot's pose (mount offset and yaw removed).
#include "core/camera_model.h"
#include "core/ceiling_layout.h"
#include "core/ceiling_map.h"
#include "core/pose.h"
#include "pipeline/camera_motion.h"
#include "pipeline/marker_observation.h"

namespace ceilpose {

struct PipelineConfig;

// Constant per configuration; computed once, then read on every frame.
class ViewGeometry {
 public:
  explicit ViewGeometry(const PipelineConfig& config);

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

// What one marker says on its own about the camera.
struct MarkerFix {
  int index = 0;  // into the observation span
  // Where the map puts the marker (its centre, rotation and sigmas).
  const MarkerPlacement* placement = nullptr;
  double world_x_m = 0.0;  // marker centre, from the map
  double world_y_m = 0.0;
  double centre_x_n = 0.0;  // level normalized image of the centre
  double centre_y_n = 0.0;
  double cam_yaw_rad = 0.0;  // camera yaw from the red→green heading
  double cam_x_m = 0.0;      // optical centre implied by this marker alone
  double cam_y_m = 0.0;
};

// Change of Axes on one marker. False when the marker's code is outside the
// layout or not on the map, or its red and green centres coincide (no
// heading). With a rolling shutter and `motion` valid, the answer is the
// camera at the centre row's instant: each of the marker's points is moved
// back by the camera's motion since its own row, so that every mode and the
// consistency checks compare answers of one instant.
bool marker_fix(const ViewGeometry& view, const MarkerObservation& marker, int index,
                const CameraMotion& motion, MarkerFix* fix);

}  // namespace ceilpose
