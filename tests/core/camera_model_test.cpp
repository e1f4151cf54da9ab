#include "core/camera_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <opencv2/calib3d.hpp>

#include "core/ceiling_layout.h"

namespace ceilpose {
namespace {

TEST(CameraModel, LevelCameraAxesFollowSpec) {
  const Pose2D robot{1.0, 2.0, 0.5};
  const CameraPose pose = camera_pose_from_robot(robot, CameraMount{});
  const double s = std::sin(0.5), c = std::cos(0.5);
  // Columns of r_wc are Xc, Yc, Zc.
  EXPECT_NEAR(pose.r_wc[0], -s, 1e-12);
  EXPECT_NEAR(pose.r_wc[3], c, 1e-12);
  EXPECT_NEAR(pose.r_wc[1], -c, 1e-12);
  EXPECT_NEAR(pose.r_wc[4], -s, 1e-12);
  EXPECT_NEAR(pose.r_wc[8], 1.0, 1e-12);
  EXPECT_NEAR(pose.t_w[2], 0.3048, 1e-12);
}

TEST(CameraModel, PointToRobotsLeftLandsRightOfImageCentre) {
  const CameraIntrinsics k;
  const CeilingLayout layout;
  // Robot faces North; its left is West.
  const CameraPose pose = camera_pose_from_robot({0, 0, std::numbers::pi / 2}, CameraMount{});
  double u = 0, v = 0;
  ASSERT_TRUE(project_world_point(k, pose, {-0.3, 0.0, layout.height_m}, &u, &v));
  EXPECT_GT(u, k.cx + 10);
  EXPECT_NEAR(v, k.cy, 1e-9);
  // A point ahead (North) lands above the centre (row 0 faces forward).
  ASSERT_TRUE(project_world_point(k, pose, {0.0, 0.3, layout.height_m}, &u, &v));
  EXPECT_LT(v, k.cy - 10);
}

TEST(CameraModel, ProjectionMatchesOpenCvWithDistortion) {
  CameraIntrinsics k;
  k.distortion = {-0.12, 0.03, 0.001, -0.0015, -0.004};
  CameraMount mount;
  mount.tilt_x_rad = 0.03;
  mount.tilt_y_rad = -0.02;
  const CameraPose pose = camera_pose_from_robot({0.4, -0.2, 1.1}, mount);
  const Mat3 r_cw = mat_transpose(pose.r_wc);
  const Vec3 t_c = mat_vec(r_cw, {-pose.t_w[0], -pose.t_w[1], -pose.t_w[2]});
  cv::Matx33d r(r_cw.data());
  cv::Vec3d rvec;
  cv::Rodrigues(r, rvec);
  const cv::Matx33d kmat(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  std::vector<cv::Point3d> pts;
  for (double x = -1.0; x <= 1.0; x += 0.25)
    for (double y = -1.0; y <= 1.0; y += 0.25) pts.emplace_back(x, y, 2.4384);
  std::vector<cv::Point2d> cv_px;
  cv::projectPoints(pts, rvec, cv::Vec3d(t_c[0], t_c[1], t_c[2]), kmat,
                    std::vector<double>(k.distortion.begin(), k.distortion.end()), cv_px);
  for (size_t i = 0; i < pts.size(); ++i) {
    double u = 0, v = 0;
    ASSERT_TRUE(project_world_point(k, pose, {pts[i].x, pts[i].y, pts[i].z}, &u, &v));
    EXPECT_NEAR(u, cv_px[i].x, 1e-6);
    EXPECT_NEAR(v, cv_px[i].y, 1e-6);
    double xn = 0, yn = 0;
    undistort_pixel(k, u, v, &xn, &yn);
    double u2 = 0, v2 = 0;
    distort_normalized(k, xn, yn, &u2, &v2);
    EXPECT_NEAR(u2 * k.fx + k.cx, u, 1e-3);
    EXPECT_NEAR(v2 * k.fy + k.cy, v, 1e-3);
  }
}

// The one geometry: the level transforms are each other's inverse and agree
// with the camera pose's axes; yaw and tilt are read back from the rotation.
TEST(CameraGeometry, LevelTransformsAgreeWithTheCameraPose) {
  const Pose2D robot{1.0, -2.0, 0.7};
  const CameraMount mount;
  const CameraPose cam = camera_pose_from_robot(robot, mount);
  const double c = std::cos(robot.yaw_rad), s = std::sin(robot.yaw_rad);
  const double dx = 0.31, dy = -0.12;
  double x = 0, y = 0, bx = 0, by = 0;
  world_to_level(c, s, dx, dy, &x, &y);
  // Camera coordinates are Rᵀ·d.
  const Vec3 p = mat_vec(mat_transpose(cam.r_wc), {dx, dy, 0.0});
  EXPECT_NEAR(x, p[0], 1e-12);
  EXPECT_NEAR(y, p[1], 1e-12);
  level_to_world(c, s, x, y, &bx, &by);
  EXPECT_NEAR(bx, dx, 1e-12);
  EXPECT_NEAR(by, dy, 1e-12);
}

TEST(CameraGeometry, YawAndTiltAreReadBackFromTheRotation) {
  for (double yaw : {-3.0, -0.4, 0.0, 1.2, 3.1})
    for (double a : {-0.05, 0.0, 0.02})
      for (double b : {-0.03, 0.0, 0.04}) {
        const Mat3 r = mat_mul(level_rotation(yaw), tilt_rotation(a, b));
        double ra = 0, rb = 0;
        camera_tilt_of(r, &ra, &rb);
        EXPECT_NEAR(camera_yaw_of(r), yaw, 1e-12);
        EXPECT_NEAR(ra, a, 1e-12);
        EXPECT_NEAR(rb, b, 1e-12);
        // level_to_tilted is the tilt's transpose.
        const Vec3 l{0.2, -0.1, 2.1};
        const Vec3 t = mat_vec(mat_transpose(tilt_rotation(a, b)), l);
        double px = 0, py = 0, pz = 0;
        level_to_tilted(a, b, l[0], l[1], l[2], &px, &py, &pz);
        EXPECT_NEAR(px, t[0], 1e-12);
        EXPECT_NEAR(py, t[1], 1e-12);
        EXPECT_NEAR(pz, t[2], 1e-12);
      }
}

TEST(CeilingLayout, SlotsAreReadNorthToSouthMsbFirst) {
  const CeilingLayout layout;
  EXPECT_NEAR(layout.slot_n_m(0), 4 * kInch_m, 1e-12);
  EXPECT_NEAR(layout.slot_n_m(1), 0.0, 1e-12);
  EXPECT_NEAR(layout.slot_n_m(2), -4 * kInch_m, 1e-12);
  EXPECT_TRUE(layout.slot_bit(4, 0));
  EXPECT_FALSE(layout.slot_bit(4, 2));
  EXPECT_TRUE(layout.slot_bit(1, 2));
}

}  // namespace
}  // namespace ceilpose
