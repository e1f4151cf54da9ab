#pragma once
// Change of Axes (thesis, one marker): what one marker says on its own about
// the camera, through the view geometry every mode shares (core/).
#include "core/view_geometry.h"
#include "pipeline/camera_motion.h"
#include "pipeline/marker_observation.h"

namespace ceilpose {

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
