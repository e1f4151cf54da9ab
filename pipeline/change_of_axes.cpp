#include "pipeline/change_of_axes.h"

#include <cmath>

namespace ceilpose {

namespace {

// Level-normalized image of a marker point, as the camera of the centre row
// would have seen it: the point was imaged tau after the centre row, when the
// camera stood its arc's tau further and was turned ω·tau more. `cam_yaw_rad` (of
// any of the frame's rows: an error of a degree in it moves a millimetre's
// correction by a few micrometres) turns the camera's axes into the world's.
void centre_row_normalized(const ViewGeometry& view, const CameraMotion& motion, double cam_yaw_rad,
                           double u_px, double v_px, double* x_n, double* y_n) {
  view.level_normalized(u_px, v_px, x_n, y_n);
  if (!motion.valid) return;
  const double tau_s = row_time_s(view.intrinsics(), v_px);
  const double depth_m = view.depth_m();
  // Offset from the camera at tau, world frame, then seen from the centre
  // row's camera.
  double dx = 0.0, dy = 0.0;
  view.ceiling_offset(cam_yaw_rad, *x_n, *y_n, &dx, &dy);
  double arc_x_m = 0.0, arc_y_m = 0.0;
  arc_displacement(motion.vx_mps, motion.vy_mps, motion.yaw_rate_radps, tau_s, &arc_x_m, &arc_y_m);
  dx += arc_x_m;
  dy += arc_y_m;
  const double yaw0 = cam_yaw_rad - motion.yaw_rate_radps * tau_s;
  world_to_level(std::cos(yaw0), std::sin(yaw0), dx / depth_m, dy / depth_m, x_n, y_n);
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
  double dx = 0.0, dy = 0.0;
  view.ceiling_offset(fix->cam_yaw_rad, fix->centre_x_n, fix->centre_y_n, &dx, &dy);
  fix->cam_x_m = fix->world_x_m - dx;
  fix->cam_y_m = fix->world_y_m - dy;
  return true;
}

}  // namespace ceilpose
