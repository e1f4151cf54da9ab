#include "sim/checkerboard.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/units.h"
#include "sim/ceiling_scene.h"

namespace ceilpose::sim {
namespace {

constexpr int kSub = 4;  // supersamples per axis

double unit(uint64_t h) { return static_cast<double>(h >> 11) * 0x1.0p-53; }

Mat3 axis_angle(double ax, double ay, double az, double angle) {
  const double c = std::cos(angle), s = std::sin(angle), v = 1.0 - c;
  return {ax * ax * v + c,      ax * ay * v - az * s, ax * az * v + ay * s,
          ax * ay * v + az * s, ay * ay * v + c,      ay * az * v - ax * s,
          ax * az * v - ay * s, ay * az * v + ax * s, az * az * v + c};
}

}  // namespace

CheckerboardCamera::CheckerboardCamera(const CameraIntrinsics& camera) : camera_(camera) {
  rays_.resize(static_cast<size_t>(camera.width) * camera.height * kSub * kSub * 2);
  size_t k = 0;
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u)
      for (int sv = 0; sv < kSub; ++sv)
        for (int su = 0; su < kSub; ++su) {
          double xn = 0.0, yn = 0.0;
          undistort_pixel(camera, u - 0.5 + (su + 0.5) / kSub, v - 0.5 + (sv + 0.5) / kSub, &xn,
                          &yn);
          rays_[k++] = static_cast<float>(xn);
          rays_[k++] = static_cast<float>(yn);
        }
}

void CheckerboardCamera::render(const Checkerboard& board, const BoardPose& pose, double noise,
                                uint64_t seed, Image* out) const {
  const CameraIntrinsics& camera = camera_;
  out->resize(camera.width, camera.height, PixelFormat::kRgb24);
  const float* ray = rays_.data();
  const Mat3 rt = mat_transpose(pose.r_cb);
  const Vec3 n = {pose.r_cb[2], pose.r_cb[5], pose.r_cb[8]};  // board normal in the camera
  const double n_dot_t = n[0] * pose.t_c[0] + n[1] * pose.t_c[1] + n[2] * pose.t_c[2];
  const double s = board.square_m;
  // The pattern spans (cols + 1) x (rows + 1) squares from (-s, -s); a
  // white border of one square around it.
  const double x0 = -2.0 * s, y0 = -2.0 * s;
  const double x1 = (board.cols + 1) * s, y1 = (board.rows + 1) * s;
  uint64_t h = mix64(seed);
  for (int v = 0; v < camera.height; ++v) {
    uint8_t* row = out->data() + static_cast<size_t>(v) * out->stride_bytes();
    for (int u = 0; u < camera.width; ++u) {
      double sum = 0.0;
      for (int sv = 0; sv < kSub; ++sv)
        for (int su = 0; su < kSub; ++su) {
          const double xn = *ray++, yn = *ray++;
          // Ray (xn, yn, 1)·λ meets the board plane n·p = n·t.
          const double denom = n[0] * xn + n[1] * yn + n[2];
          double level = 0.45;  // background
          if (std::abs(denom) > 1e-9) {
            const double lambda = n_dot_t / denom;
            if (lambda > 0.0) {
              const Vec3 p{lambda * xn - pose.t_c[0], lambda * yn - pose.t_c[1],
                           lambda - pose.t_c[2]};
              const Vec3 b = mat_vec(rt, p);
              if (b[0] >= x0 && b[0] <= x1 && b[1] >= y0 && b[1] <= y1) {
                level = 0.9;
                if (b[0] >= -s && b[0] <= board.cols * s && b[1] >= -s && b[1] <= board.rows * s) {
                  const int ci = static_cast<int>(std::floor(b[0] / s)) + 1;
                  const int cj = static_cast<int>(std::floor(b[1] / s)) + 1;
                  if ((ci + cj) % 2 == 0) level = 0.08;
                }
              }
            }
          }
          sum += level;
        }
      h = mix64(h);
      const double n1 = unit(h), n2 = unit(mix64(h ^ 0x9E37));
      const double g =
          std::sqrt(-2.0 * std::log(n1 + 1e-300)) * std::cos(2 * std::numbers::pi * n2);
      const double value = std::clamp(255.0 * sum / (kSub * kSub) + noise * g, 0.0, 255.0);
      const auto byte = static_cast<uint8_t>(std::lround(value));
      row[3 * u] = row[3 * u + 1] = row[3 * u + 2] = byte;
    }
  }
}

std::vector<BoardPose> checkerboard_views(const CameraIntrinsics& camera, const Checkerboard& board,
                                          int count, uint64_t seed) {
  std::vector<BoardPose> views;
  const double w = (board.cols - 1) * board.square_m, hgt = (board.rows - 1) * board.square_m;
  uint64_t h = mix64(seed ^ 0xB0A4D);
  auto next = [&] { return unit(h = mix64(h)); };
  for (int attempt = 0; static_cast<int>(views.size()) < count && attempt < 100000; ++attempt) {
    const double dist = 0.35 + 0.55 * next();
    const double tilt = (10.0 + 35.0 * next()) * kRadPerDeg;
    const double dir = 2.0 * std::numbers::pi * next();
    const double spin = (next() - 0.5) * 0.6;
    // Board facing the camera (its normal along -z), then tilted and spun.
    const Mat3 facing{1, 0, 0, 0, 1, 0, 0, 0, 1};
    const Mat3 r = mat_mul(axis_angle(std::cos(dir), std::sin(dir), 0.0, tilt),
                           mat_mul(axis_angle(0, 0, 1, spin), facing));
    // Where in the image its centre falls: anywhere the pattern still fits.
    const double xn = (next() - 0.5) * 1.9 * (camera.width / camera.fx) * 0.5;
    const double yn = (next() - 0.5) * 1.9 * (camera.height / camera.fy) * 0.5;
    const Vec3 centre_b{0.5 * w, 0.5 * hgt, 0.0};
    const Vec3 rc = mat_vec(r, centre_b);
    BoardPose pose{r, {xn * dist - rc[0], yn * dist - rc[1], dist - rc[2]}};
    bool inside = true;
    for (int j = -1; j <= board.rows && inside; ++j)
      for (int i = -1; i <= board.cols && inside; ++i) {
        const Vec3 b{i * board.square_m, j * board.square_m, 0.0};
        const Vec3 pc = mat_vec(r, b);
        double u = 0.0, v = 0.0;
        inside =
            project_camera_point(
                camera, {pc[0] + pose.t_c[0], pc[1] + pose.t_c[1], pc[2] + pose.t_c[2]}, &u, &v) &&
            u > 8 && v > 8 && u < camera.width - 9 && v < camera.height - 9;
      }
    if (inside) views.push_back(pose);
  }
  return views;
}

}  // namespace ceilpose::sim
