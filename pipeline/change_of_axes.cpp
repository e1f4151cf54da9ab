#include "pipeline/change_of_axes.h"

#include <cmath>

#include "pipeline/pipeline_config.h"

namespace ceilpose {

ViewGeometry::ViewGeometry(const PipelineConfig& config)
    : intrinsics_(config.intrinsics),
      mount_(config.mount),
      layout_(config.layout),
      map_(config.map ? *config.map : CeilingMap(config.layout)),
      depth_m_(config.layout.height_m - config.mount.lens_height_m),
      tilt_(tilt_rotation(config.mount.tilt_x_rad, config.mount.tilt_y_rad)) {}

void ViewGeometry::level_normalized(double u_px, double v_px, double* x_n, double* y_n) const {
  double x = 0.0, y = 0.0;
  undistort_pixel(intrinsics_, u_px, v_px, &x, &y);
  // The camera axes in the world are Level(yaw)·tilt (core/camera_model.cpp),
  // so tilt·ray is the ray in the level camera's frame.
  const Vec3 r = mat_vec(tilt_, {x, y, 1.0});
  *x_n = r[0] / r[2];
  *y_n = r[1] / r[2];
}

Pose2D ViewGeometry::robot_from_camera(double cam_x_m, double cam_y_m, double cam_yaw_rad) const {
  const double yaw = wrap_angle_rad(cam_yaw_rad - mount_.yaw_rad);
  double ox_m = 0.0, oy_m = 0.0;
  mount_offset_world(mount_, yaw, &ox_m, &oy_m);
  return Pose2D{cam_x_m - ox_m, cam_y_m - oy_m, yaw};
}

namespace {

// Level-normalized image of a marker point, as the camera of the centre row
// would have seen it: the point was imaged tau after the centre row, when the
// camera stood v·tau further and was turned ω·tau more. `cam_yaw_rad` (of
// any of the frame's rows: an error of a degree in it moves a millimetre's
// correction by a few micrometres) turns the camera's axes into the world's.
void centre_row_normalized(const ViewGeometry& view, const CameraMotion& motion, double cam_yaw_rad,
                           double u_px, double v_px, double* x_n, double* y_n) {
  view.level_normalized(u_px, v_px, x_n, y_n);
  if (!motion.valid) return;
  const double tau_s = row_time_s(view.intrinsics(), v_px);
  const double depth_m = view.depth_m();
  // Offset from the camera at tau, world frame (SPEC §3 level axes).
  const double st = std::sin(cam_yaw_rad), ct = std::cos(cam_yaw_rad);
  const double xc = depth_m * *x_n, yc = depth_m * *y_n;
  const double dx = -st * xc - ct * yc + motion.vx_mps * tau_s;
  const double dy = ct * xc - st * yc + motion.vy_mps * tau_s;
  const double yaw0 = cam_yaw_rad - motion.yaw_rate_radps * tau_s;
  const double s0 = std::sin(yaw0), c0 = std::cos(yaw0);
  *x_n = (-s0 * dx + c0 * dy) / depth_m;
  *y_n = (-c0 * dx - s0 * dy) / depth_m;
}

}  // namespace

// Change of Axes (thesis): the marker's image offset from the image centre,
// rotated by the heading and scaled by pixels per grid unit, is the marker's
// position relative to the camera; translate by the marker's grid position.
//
// With the level camera of SPEC §3 a ceiling point at d = P − C (world) has
// Xc = −sinψ·dx + cosψ·dy, Yc = −cosψ·dx − sinψ·dy, Zc = H − h. Working in
// normalized coordinates (pixels / f) the scale fx·g/(H−h) becomes (H−h),
// and the inverse rotation is the transpose:
//   dx = −sinψ·Xc − cosψ·Yc,  dy = cosψ·Xc − sinψ·Yc.
// World West (−1, 0) images as (Xc, Yc) ∝ (sinψ, cosψ), so the red→green
// vector in the image gives ψ = atan2(Δx, Δy) for a marker in its nominal
// orientation.
bool marker_fix(const ViewGeometry& view, const MarkerObservation& marker, int index,
                const CameraMotion& motion, MarkerFix* fix) {
  const MarkerPlacement* placement = view.map().find(marker.code_i, marker.code_j);
  if (placement == nullptr) return false;
  double xr = 0.0, yr = 0.0, xg = 0.0, yg = 0.0;
  view.level_normalized(marker.red_u_px, marker.red_v_px, &xr, &yr);
  view.level_normalized(marker.green_u_px, marker.green_v_px, &xg, &yg);
  double hx = xg - xr, hy = yg - yr;
  // The negated test also refuses NaN from a non-finite measurement.
  if (!(hx * hx + hy * hy >= 1e-12) || !std::isfinite(hx) || !std::isfinite(hy)) return false;
  // A marker turned by θ shows its red→green vector turned by θ too: the
  // image gives ψ − θ.
  fix->cam_yaw_rad = wrap_angle_rad(std::atan2(hx, hy) + placement->yaw_rad);
  // Rolling shutter: red and green are read at different rows, so the
  // heading, like the centre, is taken at the centre row.
  const CameraMotion still{};
  const CameraMotion& m = motion.valid && view.intrinsics().readout_ms > 0.0 ? motion : still;
  if (m.valid) {
    centre_row_normalized(view, m, fix->cam_yaw_rad, marker.red_u_px, marker.red_v_px, &xr, &yr);
    centre_row_normalized(view, m, fix->cam_yaw_rad, marker.green_u_px, marker.green_v_px, &xg,
                          &yg);
    hx = xg - xr;
    hy = yg - yr;
    if (!(hx * hx + hy * hy >= 1e-12) || !std::isfinite(hx) || !std::isfinite(hy)) return false;
  }
  centre_row_normalized(view, m, fix->cam_yaw_rad, marker.centre_u_px, marker.centre_v_px,
                        &fix->centre_x_n, &fix->centre_y_n);
  if (!std::isfinite(fix->centre_x_n) || !std::isfinite(fix->centre_y_n)) return false;
  fix->cam_yaw_rad = wrap_angle_rad(std::atan2(hx, hy) + placement->yaw_rad);
  fix->index = index;
  fix->placement = placement;
  fix->world_x_m = placement->x_m;
  fix->world_y_m = placement->y_m;
  const double s = std::sin(fix->cam_yaw_rad), c = std::cos(fix->cam_yaw_rad);
  const double xc = view.depth_m() * fix->centre_x_n, yc = view.depth_m() * fix->centre_y_n;
  fix->cam_x_m = fix->world_x_m - (-s * xc - c * yc);
  fix->cam_y_m = fix->world_y_m - (c * xc - s * yc);
  return true;
}

}  // namespace ceilpose
