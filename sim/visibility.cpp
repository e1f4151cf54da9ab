#include "sim/visibility.h"

#include <algorithm>
#include <cmath>

namespace ceilpose::sim {
namespace {

// Points sampled per outline edge: with lens distortion a straight edge
// projects to a curve that can bulge out of the image between its corners.
constexpr int kSamplesPerEdge = 16;

// Largest undistorted normalized radius that the image border reaches. The
// plumb_bob polynomial folds back far outside the field of view, so a point
// beyond this radius could project into the image while really out of view.
double max_view_radius(const CameraIntrinsics& k) {
  double r_max = 0.0;
  constexpr int kSteps = 32;
  for (int s = 0; s <= kSteps; ++s) {
    const double f = static_cast<double>(s) / kSteps;
    const double us[4] = {-0.5 + f * k.width, -0.5 + f * k.width, -0.5, k.width - 0.5};
    const double vs[4] = {-0.5, k.height - 0.5, -0.5 + f * k.height, -0.5 + f * k.height};
    for (int e = 0; e < 4; ++e) {
      double x = 0.0, y = 0.0;
      undistort_pixel(k, us[e], vs[e], &x, &y);
      r_max = std::max(r_max, std::hypot(x, y));
    }
  }
  return r_max;
}

bool outline_inside(const CameraIntrinsics& k, const CameraPose& camera, double r_max,
                    const std::array<Vec3, 4>& corners) {
  const Mat3 r_cw = mat_transpose(camera.r_wc);
  for (int e = 0; e < 4; ++e) {
    const Vec3& a = corners[e];
    const Vec3& b = corners[(e + 1) % 4];
    for (int s = 0; s < kSamplesPerEdge; ++s) {
      const double f = static_cast<double>(s) / kSamplesPerEdge;
      const Vec3 d{a[0] + f * (b[0] - a[0]) - camera.t_w[0],
                   a[1] + f * (b[1] - a[1]) - camera.t_w[1],
                   a[2] + f * (b[2] - a[2]) - camera.t_w[2]};
      const Vec3 p = mat_vec(r_cw, d);
      if (p[2] <= 1e-9 || std::hypot(p[0] / p[2], p[1] / p[2]) > r_max) return false;
      double u = 0.0, v = 0.0;
      if (!project_camera_point(k, p, &u, &v)) return false;
      if (u < -0.5 || v < -0.5 || u > k.width - 0.5 || v > k.height - 0.5) return false;
    }
  }
  return true;
}

}  // namespace

std::array<Vec3, 4> marker_outline_w(const CeilingLayout& layout, int i, int j) {
  const Vec3 c = layout.marker_centre_w(i, j);
  const double he = layout.rect_width_m, hn = 0.5 * layout.rect_height_m;
  return {Vec3{c[0] + he, c[1] + hn, c[2]}, Vec3{c[0] - he, c[1] + hn, c[2]},
          Vec3{c[0] - he, c[1] - hn, c[2]}, Vec3{c[0] + he, c[1] - hn, c[2]}};
}

bool marker_whole_in_view(const SceneOptions& options, const CameraPose& camera, int i, int j) {
  return outline_inside(options.intrinsics, camera, max_view_radius(options.intrinsics),
                        marker_outline_w(options.layout, i, j));
}

int count_whole_markers(const SceneOptions& options, const Pose2D& robot,
                        const CameraMount& mount) {
  const CameraPose camera = camera_pose_from_robot(robot, mount);
  const double r_max = max_view_radius(options.intrinsics);
  const int n = options.layout.codes();
  int count = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (outline_inside(options.intrinsics, camera, r_max, marker_outline_w(options.layout, i, j)))
        ++count;
  return count;
}

}  // namespace ceilpose::sim
