#include "core/camera_model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ceilpose {

bool CameraIntrinsics::has_distortion() const {
  for (double d : distortion) {
    if (d != 0.0) return true;
  }
  return false;
}

Mat3 tilt_rotation(double tilt_x_rad, double tilt_y_rad) {
  const double ca = std::cos(tilt_x_rad), sa = std::sin(tilt_x_rad);
  const double cb = std::cos(tilt_y_rad), sb = std::sin(tilt_y_rad);
  const Mat3 rx{1, 0, 0, 0, ca, -sa, 0, sa, ca};
  const Mat3 ry{cb, 0, sb, 0, 1, 0, -sb, 0, cb};
  return mat_mul(rx, ry);
}

Mat3 level_rotation(double yaw_rad) {
  const double s = std::sin(yaw_rad), c = std::cos(yaw_rad);
  return {-s, -c, 0.0, c, -s, 0.0, 0.0, 0.0, 1.0};
}

// R = Level(ψ)·Rx(a)·Ry(b) has Yc = (−cos a·cos ψ, −cos a·sin ψ, sin a).
double camera_yaw_of(const Mat3& r) { return std::atan2(-r[4], -r[1]); }

// M = Level(ψ)ᵀR = Rx(a)Ry(b) = [[cb, 0, sb], [sa·sb, ca, −sa·cb], [−ca·sb, sa, ca·cb]].
void camera_tilt_of(const Mat3& r, double* a, double* b) {
  const Mat3 m = mat_mul(mat_transpose(level_rotation(camera_yaw_of(r))), r);
  *a = std::atan2(-m[5], m[8]);
  *b = std::asin(std::clamp(m[2], -1.0, 1.0));
}

CameraPose camera_pose_from_robot(const Pose2D& robot, const CameraMount& mount) {
  double ox_m = 0.0, oy_m = 0.0;
  mount_offset_world(mount, robot.yaw_rad, &ox_m, &oy_m);
  CameraPose pose;
  pose.t_w = {robot.x_m + ox_m, robot.y_m + oy_m, mount.lens_height_m};
  pose.r_wc = mat_mul(level_rotation(robot.yaw_rad + mount.yaw_rad),
                      tilt_rotation(mount.tilt_x_rad, mount.tilt_y_rad));
  return pose;
}

void distort_normalized(const CameraIntrinsics& k, double x, double y, double* xd, double* yd) {
  plumb_bob(k.distortion.data(), x, y, xd, yd);
}

bool project_camera_point(const CameraIntrinsics& k, const Vec3& p, double* u_px, double* v_px) {
  if (p[2] <= 1e-9) return false;
  double xd = 0.0, yd = 0.0;
  distort_normalized(k, p[0] / p[2], p[1] / p[2], &xd, &yd);
  *u_px = k.fx * xd + k.cx;
  *v_px = k.fy * yd + k.cy;
  return true;
}

bool project_world_point(const CameraIntrinsics& k, const CameraPose& pose, const Vec3& pw,
                         double* u_px, double* v_px) {
  const Vec3 d{pw[0] - pose.t_w[0], pw[1] - pose.t_w[1], pw[2] - pose.t_w[2]};
  return project_camera_point(k, mat_vec(mat_transpose(pose.r_wc), d), u_px, v_px);
}

void undistort_pixel(const CameraIntrinsics& k, double u_px, double v_px, double* x_n,
                     double* y_n) {
  const double xd = (u_px - k.cx) / k.fx, yd = (v_px - k.cy) / k.fy;
  if (!k.has_distortion()) {
    *x_n = xd;
    *y_n = yd;
    return;
  }
  const double k1 = k.distortion[0], k2 = k.distortion[1], p1 = k.distortion[2],
               p2 = k.distortion[3], k3 = k.distortion[4];
  double x = xd, y = yd;
  // Fixed-point iteration as in cv::undistortPoints; converges for the mild
  // distortion of ceiling cameras.
  for (int i = 0; i < 20; ++i) {
    const double r2 = x * x + y * y;
    const double icdist = 1.0 / (1.0 + r2 * (k1 + r2 * (k2 + r2 * k3)));
    const double dx = 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    const double dy = p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    x = (xd - dx) * icdist;
    y = (yd - dy) * icdist;
  }
  *x_n = x;
  *y_n = y;
}

std::string distortion_problem(const CameraIntrinsics& k) {
  if (!k.has_distortion()) return {};
  // The border of the image's central half, 16 samples a side. Not the
  // image's own border: a very wide lens whose corners the fixed-point
  // inverse cannot reach still localizes everywhere else.
  constexpr int kSamplesPerSide = 16;
  const double w = 0.5 * (k.width - 1), h = 0.5 * (k.height - 1);
  const double u0 = 0.25 * (k.width - 1), v0 = 0.25 * (k.height - 1);
  for (int side = 0; side < 4; ++side) {
    for (int i = 0; i <= kSamplesPerSide; ++i) {
      const double t = static_cast<double>(i) / kSamplesPerSide;
      const double u = u0 + (side == 0 ? t * w : side == 1 ? w : side == 2 ? (1 - t) * w : 0.0);
      const double v = v0 + (side == 0 ? 0.0 : side == 1 ? t * h : side == 2 ? h : (1 - t) * h);
      double x = 0, y = 0, xd = 0, yd = 0;
      undistort_pixel(k, u, v, &x, &y);
      distort_normalized(k, x, y, &xd, &yd);
      const double miss_px = std::hypot(xd * k.fx + k.cx - u, yd * k.fy + k.cy - v);
      if (!(miss_px <= kMaxDistortionRoundTripPx)) {
        char text[160];
        std::snprintf(text, sizeof text,
                      "the distortion cannot be inverted at pixel (%.0f, %.0f) (round trip off "
                      "by %.3g px; at most %.1f px)",
                      u, v, miss_px, kMaxDistortionRoundTripPx);
        return text;
      }
    }
  }
  return {};
}

}  // namespace ceilpose
