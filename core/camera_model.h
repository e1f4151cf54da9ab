#pragma once
// The camera model of SPEC §3: OpenCV pinhole + plumb_bob distortion, the
// camera mounted on the robot looking up, row 0 towards the robot's forward.
#include <array>
#include <cmath>
#include <string>

#include "core/pose.h"

namespace ceilpose {

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<double, 9>;  // row-major

struct CameraIntrinsics {
  int width = 640;
  int height = 480;
  double fx = 530.0;
  double fy = 530.0;
  double cx = 319.5;
  double cy = 239.5;
  std::array<double, 5> distortion{0.0, 0.0, 0.0, 0.0, 0.0};  // k1 k2 p1 p2 k3
  // Rolling shutter (SPEC §3): first row to last, milliseconds; 0 = global.
  // Not part of a camera_info calibration (§9): a calibration keeps it.
  double readout_ms = 0.0;

  bool has_distortion() const;
  bool operator==(const CameraIntrinsics&) const = default;
};

// The camera's keys (SPEC §3, §4): recording.yaml's camera block, the
// configuration's camera section and `inspect` name them alike.
namespace camera_keys {
inline constexpr const char* kWidth = "width";
inline constexpr const char* kHeight = "height";
inline constexpr const char* kFx = "fx";
inline constexpr const char* kFy = "fy";
inline constexpr const char* kCx = "cx";
inline constexpr const char* kCy = "cy";
inline constexpr const char* kDistortion = "distortion";
inline constexpr const char* kReadoutMs = "readout_ms";
}  // namespace camera_keys

// The longest rolling-shutter readout accepted (SPEC §3), milliseconds.
inline constexpr double kMaxReadoutMs = 1000.0;

// The largest image ceilpose takes (configuration and recordings alike):
// 8192 px a side and 32 Mpx, a 12 MP sensor with room to spare. The
// pipeline's buffers are ~20 bytes a pixel; a recording.yaml saying
// 100000x100000 must be refused, not allocated.
inline constexpr int kMaxImageSidePx = 8192;
inline constexpr long kMaxImagePixels = 32L * 1024 * 1024;

// SPEC §3: when pixel row v_px (fractional) was exposed, seconds after the
// centre row; 0 for a global shutter.
inline double row_time_s(const CameraIntrinsics& k, double v_px) {
  return (v_px - 0.5 * (k.height - 1)) / k.height * (k.readout_ms * 1e-3);
}

// Where the camera sits on the robot. SPEC defaults: lens 0.3048 m above the
// floor, at the robot origin, no mounting yaw, no tilt.
struct CameraMount {
  double lens_height_m = 0.3048;
  double offset_forward_m = 0.0;
  double offset_left_m = 0.0;
  double yaw_rad = 0.0;     // camera forward (image up) relative to robot forward, CCW
  double tilt_x_rad = 0.0;  // rotation about the camera's Xc axis (image right)
  double tilt_y_rad = 0.0;  // rotation about the camera's Yc axis (image down)
};

// Where the lens sits relative to the robot's origin, world frame, for a
// robot heading yaw_rad: the mount offset turned by the heading.
inline void mount_offset_world(const CameraMount& mount, double yaw_rad, double* x_m, double* y_m) {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  *x_m = mount.offset_forward_m * c - mount.offset_left_m * s;
  *y_m = mount.offset_forward_m * s + mount.offset_left_m * c;
}

// Rigid camera pose in the world: p_world = R_wc * p_cam + t_w.
struct CameraPose {
  Mat3 r_wc{};  // columns are the camera axes Xc, Yc, Zc in world coordinates
  Vec3 t_w{};   // optical centre in the world
};

// ---- The camera's geometry (SPEC §3), written once. Every positioning
// mode, the survey and calibration call these; templates serve Ceres'
// automatic derivatives.
//
// The level camera of yaw ψ (image up's heading on the floor) has world axes
// Xc = (−sin ψ, cos ψ, 0), Yc = (−cos ψ, −sin ψ, 0), Zc = (0, 0, 1). A tilted
// camera is R_wc = Level(ψ)·Rx(a)·Ry(b): tilt a about Xc, then b about Yc.

// A world offset (dx, dy) from the optical centre in the level camera's
// (X, Y): X = −sin ψ·dx + cos ψ·dy, Y = −cos ψ·dx − sin ψ·dy.
template <typename T>
void world_to_level(const T& cos_yaw, const T& sin_yaw, const T& dx, const T& dy, T* x, T* y) {
  *x = -sin_yaw * dx + cos_yaw * dy;
  *y = -cos_yaw * dx - sin_yaw * dy;
}

// The inverse (the transpose): dx = −sin ψ·X − cos ψ·Y, dy = cos ψ·X − sin ψ·Y.
template <typename T>
void level_to_world(const T& cos_yaw, const T& sin_yaw, const T& x, const T& y, T* dx, T* dy) {
  *dx = -sin_yaw * x - cos_yaw * y;
  *dy = cos_yaw * x - sin_yaw * y;
}

// A point (lx, ly, lz) of the level camera's frame in the tilted camera's:
// Ry(b)ᵀ·Rx(a)ᵀ·l.
template <typename T>
void level_to_tilted(const T& tilt_x_rad, const T& tilt_y_rad, const T& lx, const T& ly,
                     const T& lz, T* px, T* py, T* pz) {
  using std::cos;
  using std::sin;
  const T ca = cos(tilt_x_rad), sa = sin(tilt_x_rad), cb = cos(tilt_y_rad), sb = sin(tilt_y_rad);
  const T q1 = ca * ly + sa * lz, q2 = -sa * ly + ca * lz;
  *px = cb * lx - sb * q2;
  *py = q1;
  *pz = sb * lx + cb * q2;
}

// The level camera's rotation Level(ψ), row-major (columns Xc, Yc, Zc).
Mat3 level_rotation(double yaw_rad);

// Rotation about Xc by a, then about Yc by b, composed as R = Rx(a) * Ry(b).
Mat3 tilt_rotation(double tilt_x_rad, double tilt_y_rad);

// The yaw ψ of R_wc = Level(ψ)·Rx(a)·Ry(b): the floor heading of −Yc (image
// up), exact for any tilt below 90°.
double camera_yaw_of(const Mat3& r_wc);

// The tilt (a, b) of R_wc = Level(ψ)·Rx(a)·Ry(b).
void camera_tilt_of(const Mat3& r_wc, double* tilt_x_rad, double* tilt_y_rad);

// SPEC §3 with the mount offset, mounting yaw and tilt applied.
CameraPose camera_pose_from_robot(const Pose2D& robot, const CameraMount& mount);

// A pixel residual in undistorted normalized coordinates: f·(observed −
// X/Z), one axis. Undistorting the observations once is cheaper than
// distorting every projection, and differentiates more simply.
inline double normalized_residual_px(double f_px, double observed_n, double p_axis, double p_z) {
  return f_px * (observed_n - p_axis / p_z);
}

// Inline: the least-squares solver calls these per point per pass (~180k
// calls in a 260-frame profile), where a call cost more than the arithmetic.
inline Mat3 mat_mul(const Mat3& a, const Mat3& b) {
  Mat3 c{};
  for (int r = 0; r < 3; ++r)
    for (int col = 0; col < 3; ++col) {
      double s = 0.0;
      for (int k = 0; k < 3; ++k) s += a[r * 3 + k] * b[k * 3 + col];
      c[r * 3 + col] = s;
    }
  return c;
}
inline Mat3 mat_transpose(const Mat3& a) {
  return {a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]};
}
inline Vec3 mat_vec(const Mat3& a, const Vec3& v) {
  return {a[0] * v[0] + a[1] * v[1] + a[2] * v[2], a[3] * v[0] + a[4] * v[1] + a[5] * v[2],
          a[6] * v[0] + a[7] * v[1] + a[8] * v[2]};
}

// OpenCV's plumb_bob on normalized coordinates, d = (k1, k2, p1, p2, k3);
// a template so that the survey's automatic derivatives use the same formula.
template <typename T, typename D>
void plumb_bob(const D* d, const T& x, const T& y, T* xd, T* yd) {
  const T r2 = x * x + y * y;
  const T radial = T(1.0) + r2 * (d[0] + r2 * (d[1] + r2 * d[4]));
  *xd = x * radial + T(2.0) * d[2] * x * y + d[3] * (r2 + T(2.0) * x * x);
  *yd = y * radial + d[2] * (r2 + T(2.0) * y * y) + T(2.0) * d[3] * x * y;
}

// Applies plumb_bob distortion to normalized coordinates (x = Xc/Zc, y = Yc/Zc).
void distort_normalized(const CameraIntrinsics& k, double x, double y, double* xd, double* yd);

// Camera-frame point to pixel. Returns false when the point is behind the camera.
bool project_camera_point(const CameraIntrinsics& k, const Vec3& p_cam, double* u_px, double* v_px);

// World point to pixel for a given camera pose.
bool project_world_point(const CameraIntrinsics& k, const CameraPose& pose, const Vec3& p_world,
                         double* u_px, double* v_px);

// Pixel to undistorted normalized coordinates (iterative inverse of plumb_bob,
// as cv::undistortPoints does).
void undistort_pixel(const CameraIntrinsics& k, double u_px, double v_px, double* x_n, double* y_n);

// Pixels of the image's central half whose undistortion, distorted back,
// misses them by more than this cannot be localized: the coefficients
// describe no lens this image could come from (a typo, 1e300).
inline constexpr double kMaxDistortionRoundTripPx = 0.5;
// Empty when the distortion can be inverted over the image's central half,
// else what fails, naming the pixel: "the distortion cannot be inverted at
// pixel (160, 120) (round trip off by 31.2 px; at most 0.5 px)".
std::string distortion_problem(const CameraIntrinsics& k);

}  // namespace ceilpose
