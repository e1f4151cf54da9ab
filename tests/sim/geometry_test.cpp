// The renderer's geometry against an independent implementation: OpenCV's
// projectPoints with a camera built straight from SPEC §3's axes.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <vector>

#include "sim/renderer.h"
#include "sim/visibility.h"
#include "tests/sim/sim_test_support.h"

namespace ceilpose::sim {
namespace {

using testing::Part;
using testing::Point2;

constexpr double kInch = 0.0254;
// The renderer's target is < 0.3 px; the area-integrating renderer measures about
// 0.005 px, so a tighter bound catches half-pixel convention slips.
constexpr double kCentroidTolerance_px = 0.05;

CameraIntrinsics distorted_camera() {
  CameraIntrinsics k;
  k.distortion = {-0.11, 0.025, 0.0012, -0.0009, -0.003};
  return k;
}

// A mount with everything SPEC §3 allows: offset, mounting yaw, tilt.
CameraMount awkward_mount() {
  CameraMount m;
  m.offset_forward_m = 0.07;
  m.offset_left_m = -0.04;
  m.yaw_rad = 0.2;
  m.tilt_x_rad = 0.025;
  m.tilt_y_rad = -0.03;
  return m;
}

// World -> camera rotation and translation for cv::projectPoints, built from
// SPEC §3's words (not from core/camera_model): level axes
// Xc=(-sin a, cos a, 0), Yc=(-cos a, -sin a, 0), Zc=(0,0,1) for the camera's
// heading a, tilted by Rx(tx)·Ry(ty) about its own axes.
void spec_extrinsics(const Pose2D& robot, const CameraMount& m, cv::Vec3d* rvec, cv::Vec3d* tvec) {
  const double a = robot.yaw_rad + m.yaw_rad;
  const cv::Matx33d level(-std::sin(a), -std::cos(a), 0, std::cos(a), -std::sin(a), 0, 0, 0, 1);
  const cv::Matx33d rx(1, 0, 0, 0, std::cos(m.tilt_x_rad), -std::sin(m.tilt_x_rad), 0,
                       std::sin(m.tilt_x_rad), std::cos(m.tilt_x_rad));
  const cv::Matx33d ry(std::cos(m.tilt_y_rad), 0, std::sin(m.tilt_y_rad), 0, 1, 0,
                       -std::sin(m.tilt_y_rad), 0, std::cos(m.tilt_y_rad));
  const cv::Matx33d r_wc = level * rx * ry;
  const double c = std::cos(robot.yaw_rad), s = std::sin(robot.yaw_rad);
  const cv::Vec3d centre(robot.x_m + m.offset_forward_m * c - m.offset_left_m * s,
                         robot.y_m + m.offset_forward_m * s + m.offset_left_m * c, m.lens_height_m);
  const cv::Matx33d r_cw = r_wc.t();
  cv::Rodrigues(r_cw, *rvec);
  *tvec = -(r_cw * centre);
}

// SPEC §2 feature points of marker (i, j), written out from the SPEC table in
// inches: the six outline vertices and the centre of every set dot.
std::vector<cv::Point3d> spec_feature_points(int i, int j, double grid_m, double height_m) {
  const double x0 = i * grid_m, y0 = j * grid_m;
  std::vector<cv::Point3d> pts;
  for (double e : {-5.0, 0.0, 5.0})
    for (double n : {-6.0, 6.0}) pts.emplace_back(x0 + e * kInch, y0 + n * kInch, height_m);
  for (int k = 0; k < 3; ++k) {
    const double n = (4.0 - 4.0 * k) * kInch;  // MSB northernmost
    if ((i >> (2 - k)) & 1) pts.emplace_back(x0 + 2.5 * kInch, y0 + n, height_m);
    if ((j >> (2 - k)) & 1) pts.emplace_back(x0 - 2.5 * kInch, y0 + n, height_m);
  }
  return pts;
}

TEST(RendererGeometry, FeaturePointsAgreeWithOpenCvProjectPoints) {
  SceneOptions options;
  options.intrinsics = distorted_camera();
  const CameraMount mount = awkward_mount();
  const Pose2D robot{2.1, 1.7, 0.8};
  Renderer renderer(options);
  cv::Vec3d rvec, tvec;
  spec_extrinsics(robot, mount, &rvec, &tvec);
  const CameraIntrinsics& k = options.intrinsics;
  const cv::Matx33d kmat(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  const std::vector<double> dist(k.distortion.begin(), k.distortion.end());
  const CameraPose camera = camera_pose_from_robot(robot, mount);
  // Metres per pixel on the ceiling, to express ray-mapping errors in pixels.
  const double m_per_px = (options.layout.height_m - mount.lens_height_m) / k.fx;
  int checked = 0;
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) {
      if (!marker_whole_in_view(options, camera, i, j)) continue;
      const auto pts = spec_feature_points(i, j, options.layout.grid_m, options.layout.height_m);
      std::vector<cv::Point2d> cv_px;
      cv::projectPoints(pts, rvec, tvec, kmat, dist, cv_px);
      for (size_t p = 0; p < pts.size(); ++p) {
        double u = 0, v = 0;
        ASSERT_TRUE(project_world_point(k, camera, {pts[p].x, pts[p].y, pts[p].z}, &u, &v));
        EXPECT_LT(std::hypot(u - cv_px[p].x, v - cv_px[p].y), 0.1) << "marker " << i << "," << j;
        // The renderer's own pixel -> ceiling ray lands back on the point.
        double x = 0, y = 0;
        ASSERT_TRUE(renderer.ceiling_point(robot, mount, cv_px[p].x, cv_px[p].y, &x, &y));
        EXPECT_LT(std::hypot(x - pts[p].x, y - pts[p].y) / m_per_px, 0.1)
            << "marker " << i << "," << j;
        ++checked;
      }
    }
  EXPECT_GT(checked, 40);
}

// Rendering scene whose background is uniform (rails painted like tiles, no
// fixtures) so that every pixel unmixes exactly into marker coverage.
SceneOptions plain_background_options() {
  SceneOptions options;
  options.intrinsics = distorted_camera();
  options.layout.rail = options.layout.tile;
  return options;
}

Effects no_fixtures() {
  Effects e;
  e.light_fixtures = false;
  return e;
}

struct Window {
  int u0, v0, u1, v1;
};

Window window_around(const CameraIntrinsics& k, const CameraPose& camera,
                     const std::vector<Vec3>& corners) {
  double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
  for (const Vec3& c : corners) {
    double u = 0, v = 0;
    project_world_point(k, camera, c, &u, &v);
    u0 = std::min(u0, u);
    v0 = std::min(v0, v);
    u1 = std::max(u1, u);
    v1 = std::max(v1, v);
  }
  constexpr int kMargin = 4;
  return {static_cast<int>(u0) - kMargin, static_cast<int>(v0) - kMargin,
          static_cast<int>(u1) + kMargin, static_cast<int>(v1) + kMargin};
}

std::vector<Vec3> rectangle_w(const CeilingLayout& l, int i, int j, double e0, double e1) {
  const Vec3 c = l.marker_centre_w(i, j);
  const double hn = 0.5 * l.rect_height_m;
  return {Vec3{c[0] + e1, c[1] + hn, c[2]}, Vec3{c[0] + e0, c[1] + hn, c[2]},
          Vec3{c[0] + e0, c[1] - hn, c[2]}, Vec3{c[0] + e1, c[1] - hn, c[2]}};
}

TEST(RendererGeometry, RectangleCentroidsOfCodeZeroMarkerLandWhereProjectionSays) {
  const SceneOptions options = plain_background_options();
  const CameraMount mount = awkward_mount();
  const Pose2D robot{0.25, 0.18, -2.3};
  Renderer renderer(options);
  Image img;
  renderer.render(robot, mount, no_fixtures(), 7, &img);
  const CameraPose camera = camera_pose_from_robot(robot, mount);
  ASSERT_TRUE(marker_whole_in_view(options, camera, 0, 0));
  const CeilingLayout& l = options.layout;
  const auto red = rectangle_w(l, 0, 0, 0.0, l.rect_width_m);
  const auto green = rectangle_w(l, 0, 0, -l.rect_width_m, 0.0);
  for (const auto& [corners, part] : {std::pair{red, Part::kRed}, std::pair{green, Part::kGreen}}) {
    const Window w = window_around(options.intrinsics, camera, corners);
    const Point2 expected =
        testing::projected_polygon_centroid(options.intrinsics, camera, corners);
    const Point2 got = testing::coverage_centroid(l, img, w.u0, w.v0, w.u1, w.v1, part);
    EXPECT_LT(std::hypot(got.u - expected.u, got.v - expected.v), kCentroidTolerance_px)
        << "expected " << expected.u << "," << expected.v << " got " << got.u << "," << got.v;
  }
}

TEST(RendererGeometry, WholeMarkerCentroidsLandWhereProjectionSaysForEveryMarkerInView) {
  const SceneOptions options = plain_background_options();
  const CameraMount mount = awkward_mount();
  const Pose2D robot{3.3, 2.2, 1.1};
  Renderer renderer(options);
  Image img;
  renderer.render(robot, mount, no_fixtures(), 11, &img);
  const CameraPose camera = camera_pose_from_robot(robot, mount);
  const CeilingLayout& l = options.layout;
  int checked = 0;
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) {
      if (!marker_whole_in_view(options, camera, i, j)) continue;
      const auto corners = rectangle_w(l, i, j, -l.rect_width_m, l.rect_width_m);
      const Window w = window_around(options.intrinsics, camera, corners);
      const Point2 expected =
          testing::projected_polygon_centroid(options.intrinsics, camera, corners);
      double coverage_px = 0.0;
      const Point2 got = testing::coverage_centroid(l, img, w.u0, w.v0, w.u1, w.v1,
                                                    Part::kWholeMarker, &coverage_px);
      EXPECT_LT(std::hypot(got.u - expected.u, got.v - expected.v), kCentroidTolerance_px)
          << "marker " << i << "," << j;
      ++checked;
    }
  EXPECT_GE(checked, 4);
}

TEST(RendererGeometry, ScaledDefaultCameraKeepsTheFieldOfView) {
  const CameraIntrinsics k = scaled_default_intrinsics(1280);
  const CameraIntrinsics d;
  EXPECT_EQ(k.width, 1280);
  EXPECT_EQ(k.height, 960);
  EXPECT_DOUBLE_EQ(k.fx, 2 * d.fx);
  EXPECT_DOUBLE_EQ(k.cx, 639.5);
  EXPECT_DOUBLE_EQ(k.cy, 479.5);
  EXPECT_DOUBLE_EQ(k.width / k.fx, d.width / d.fx);
}

}  // namespace
}  // namespace ceilpose::sim
