#include "pipeline/lsq_solver.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "pipeline/lsq_terms.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/positioner.h"
#include "positioning_support.h"

namespace ceilpose {
namespace {

double position_error_m(const PoseEstimate& est, const Pose2D& truth) {
  return std::hypot(est.pose.x_m - truth.x_m, est.pose.y_m - truth.y_m);
}

// A fit that holds the tilt or the motion never reads their columns: left
// out, they are zero, and every other column is what the whole Jacobian
// gives, for a centroid and for an edge point under a moving rolling
// shutter.
TEST(PointJacobian, ColumnsLeftOutAreZeroAndTheOthersUnchanged) {
  PipelineConfig config;
  const ViewGeometry view(config);
  LsqState st;
  st.t_w = {2.0, 2.0, 0.3};
  st.r_wc = {0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0};
  st.vx = 0.8, st.vy = -0.3, st.w = 0.6;
  st.edge_weight = 1.7;
  const PointCamera centre = centre_camera(st);
  for (const bool edge : {false, true}) {
    LsqPoint pt{0.05, 0.04, {2.1, 2.08, 2.4384}, 0, 0.004};
    if (edge) pt.normal_x = 0.6, pt.normal_y = 0.8;
    const PointCamera cam = point_camera(st, pt, centre, true);
    double all_x[kLsqParams], all_y[kLsqParams];
    point_jacobian(view, pt, cam, all_x, all_y, true, true);
    for (const bool tilt : {false, true}) {
      for (const bool motion : {false, true}) {
        double jx[kLsqParams], jy[kLsqParams];
        point_jacobian(view, pt, cam, jx, jy, tilt, motion);
        for (int c = 0; c < kLsqParams; ++c) {
          const bool left_out = (!tilt && (c == kLsqTiltX || c == kLsqTiltY)) ||
                                (!motion && (c == kLsqVx || c == kLsqVy || c == kLsqYawRate));
          EXPECT_EQ(jx[c], left_out ? 0.0 : all_x[c]) << edge << tilt << motion << " column " << c;
          EXPECT_EQ(jy[c], left_out ? 0.0 : all_y[c]) << edge << tilt << motion << " column " << c;
          // The columns left out are not zero in the whole Jacobian.
          if (c >= kLsqTiltX && c <= kLsqYawRate && c != kLsqTz) {
            EXPECT_NE(all_x[c], 0.0) << edge << " column " << c;
          }
        }
      }
    }
  }
}

// What accumulate keeps for the covariance at the same state: each point
// in use, its residual and the Jacobian point_residual and point_jacobian
// give under the model's columns; a point whose marker is not in use, only
// that it was not kept. The normal equations are the same with and without.
TEST(PointTerms, AccumulateKeepsEachPointInUseAsPointResidualAndJacobianGiveIt) {
  PipelineConfig config;
  const ViewGeometry view(config);
  const PositioningParams& params = config.positioning;
  LsqState st;
  st.t_w = {2.0, 2.0, 0.3};
  st.r_wc = {0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0};
  st.vx = 0.8, st.vy = -0.3, st.w = 0.6;
  const PointCamera centre = centre_camera(st);
  std::array<LsqPoint, 3> points{LsqPoint{0.05, 0.04, {2.1, 2.08, 2.4384}, 0, 0.004},
                                 LsqPoint{-0.03, 0.02, {1.95, 2.03, 2.4384}, 1, -0.002},
                                 LsqPoint{0.01, -0.06, {2.02, 1.9, 2.4384}, 0, 0.001}};
  points[2].normal_x = 0.6, points[2].normal_y = 0.8;
  const std::array<bool, 2> use{true, false};
  LsqModel model;
  model.active = {true, true, true, false, false, false, true, true, true, true};
  std::array<PointTerms, 3> terms;
  terms[1].kept = true;  // stale: accumulate must clear it
  LsqNormal a{}, a_without{};
  LsqVector b{}, b_without{};
  double wr2 = 0.0, wr2_without = 0.0;
  int n = 0, n_without = 0;
  const double cost =
      accumulate(view, params, points, use, st, model, true, &a, &b, &wr2, &n, terms);
  const double cost_without = accumulate(view, params, points, use, st, model, true, &a_without,
                                         &b_without, &wr2_without, &n_without);
  EXPECT_EQ(cost, cost_without);
  EXPECT_EQ(a, a_without);
  EXPECT_EQ(b, b_without);
  EXPECT_EQ(n, 3);
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(terms[i].kept, use[static_cast<size_t>(points[i].fix)]) << "point " << i;
    if (!terms[i].kept) continue;
    const PointCamera cam = point_camera(st, points[i], centre, true);
    double rx = 0.0, ry = 0.0;
    ASSERT_TRUE(point_residual(view, points[i], cam, &rx, &ry));
    double jx[kLsqParams], jy[kLsqParams];
    point_jacobian(view, points[i], cam, jx, jy, model.tilt_free(), model.motion_free());
    EXPECT_EQ(terms[i].rx, rx) << "point " << i;
    EXPECT_EQ(terms[i].ry, ry) << "point " << i;
    for (int c = 0; c < kLsqParams; ++c) {
      EXPECT_EQ(terms[i].jx[c], jx[c]) << "point " << i << " column " << c;
      EXPECT_EQ(terms[i].jy[c], jy[c]) << "point " << i << " column " << c;
    }
  }
}

TEST(LeastSquares, RecoversExactPose) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  const Pose2D robot{2.2, 1.9, 2.8};
  const PoseEstimate est =
      positioner.solve(testing::observe(view, robot), PositioningMode::kLeastSquares);
  ASSERT_TRUE(est.valid);
  EXPECT_EQ(est.mode, PositioningMode::kLeastSquares);
  EXPECT_LT(position_error_m(est, robot), 1e-6);
  EXPECT_NEAR(wrap_angle_rad(est.pose.yaw_rad - robot.yaw_rad), 0.0, 1e-6);
  EXPECT_LT(est.rms_residual_px, 1e-4);
}

// Edge points are measured across their edge only, and wherever a camera's
// gamma, glare or blur puts a dark-on-light step's half-way level: here
// every edge's image is 0.3 px outside the edge and its along-edge position
// 2 px off. The solve takes the offset as an unknown and the pose is exact.
TEST(LeastSquares, EdgePointsCountAcrossTheEdgeAndTheirCommonOffsetIsSolved) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  view.mount.tilt_x_rad = 0.02;  // a tilted camera: the case edges are for
  const Pose2D robot{2.2, 1.9, 2.8};
  std::vector<MarkerObservation> markers = testing::observe(view, robot);
  const CameraPose pose = camera_pose_from_robot(robot, view.mount);
  const CeilingLayout& l = view.layout;
  for (MarkerObservation& m : markers) {
    m.point_count = 3;  // centre and the two centroids; then the four ends
    m.points[0] = {0.0, 0.0, m.centre_u_px, m.centre_v_px};
    m.points[1] = {l.red_centre_e_m(), 0.0, m.red_u_px, m.red_v_px};
    m.points[2] = {l.green_centre_e_m(), 0.0, m.green_u_px, m.green_v_px};
    const Vec3 c = l.marker_centre_w(m.code_i, m.code_j);
    for (double e : {l.red_centre_e_m(), l.green_centre_e_m()})
      for (double side : {1.0, -1.0}) {
        const double n = side * 0.5 * l.rect_height_m;
        double u = 0, v = 0, u2 = 0, v2 = 0, u3 = 0, v3 = 0;
        ASSERT_TRUE(project_world_point(view.intrinsics, pose, {c[0] + e, c[1] + n, c[2]}, &u, &v));
        ASSERT_TRUE(project_world_point(view.intrinsics, pose,
                                        {c[0] + e, c[1] + n + side * 1e-3, c[2]}, &u2, &v2));
        ASSERT_TRUE(project_world_point(view.intrinsics, pose, {c[0] + e + 1e-3, c[1] + n, c[2]},
                                        &u3, &v3));
        // Along the edge: the image of East; across it, its perpendicular
        // on the side North (outwards) lies.
        const double au = (u3 - u) / std::hypot(u3 - u, v3 - v);
        const double av = (v3 - v) / std::hypot(u3 - u, v3 - v);
        const double out = (u2 - u) * -av + (v2 - v) * au > 0.0 ? 1.0 : -1.0;
        const double nu = -av * out, nv = au * out;
        m.points[m.point_count++] = {e,  n, u + 0.3 * nu + 2.0 * au, v + 0.3 * nv + 2.0 * av,
                                     nu, nv};
      }
  }
  const PoseEstimate est = positioner.solve(markers, PositioningMode::kLeastSquares);
  ASSERT_TRUE(est.valid);
  // Not exact: the tilt's soft prior (lsq_tilt_prior_rad) draws it a little
  // towards level. Measured: 8 µm, 4 µrad, 0.0002 px.
  EXPECT_LT(position_error_m(est, robot), 2e-5);
  EXPECT_NEAR(positioner.last_lsq().edge_offset_px, 0.3, 1e-3);
  EXPECT_NEAR(positioner.last_lsq().tilt_x_rad, 0.02, 1e-5);
  EXPECT_LT(est.rms_residual_px, 1e-3);
  EXPECT_EQ(positioner.last_lsq().points, 7 * static_cast<int>(markers.size()));
}

TEST(LeastSquares, RecoversRobotPositionUnderUnknownTilt) {
  PipelineConfig config;  // configured level; the real camera is tilted 3°
  Positioner positioner(config);
  testing::SyntheticView view;
  view.mount.tilt_x_rad = 0.04;
  view.mount.tilt_y_rad = -0.03;
  const Pose2D robot{2.0, 2.4, 0.9};
  const PoseEstimate est =
      positioner.solve(testing::observe(view, robot), PositioningMode::kLeastSquares);
  ASSERT_TRUE(est.valid);
  // Change of Axes would be off by (H−h)·tan(3°) ≈ 11 cm.
  EXPECT_LT(position_error_m(est, robot), 1e-3);
  EXPECT_NEAR(wrap_angle_rad(est.pose.yaw_rad - robot.yaw_rad), 0.0, 1e-3);
  EXPECT_NEAR(positioner.last_lsq().tilt_x_rad, 0.04, 1e-3);
  EXPECT_NEAR(positioner.last_lsq().tilt_y_rad, -0.03, 1e-3);
}

TEST(LeastSquares, TiltedViewFoolsChangeOfAxesButNotLeastSquares) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  view.mount.tilt_x_rad = 0.05;
  const Pose2D robot{2.0, 2.4, 0.0};
  const auto markers = testing::observe(view, robot);
  const PoseEstimate axes = positioner.solve(markers, PositioningMode::kChangeOfAxes);
  const PoseEstimate lsq = positioner.solve(markers, PositioningMode::kLeastSquares);
  ASSERT_TRUE(axes.valid);
  ASSERT_TRUE(lsq.valid);
  EXPECT_GT(position_error_m(axes, robot), 0.05);
  EXPECT_LT(position_error_m(lsq, robot), 1e-3);
}

TEST(LeastSquares, RejectsOutlierMarkerWithWrongCode) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  view.noise_px = 0.2;
  const Pose2D robot{2.1, 2.0, -0.6};
  auto markers = testing::observe(view, robot);
  ASSERT_GE(markers.size(), 5u);
  markers[2].code_i ^= 2;
  const PoseEstimate est = positioner.solve(markers, PositioningMode::kLeastSquares);
  ASSERT_TRUE(est.valid);
  EXPECT_EQ(est.markers, static_cast<int>(markers.size()) - 1);
  EXPECT_LT(position_error_m(est, robot), 3e-3);
}

TEST(LeastSquares, DropsMarkerWhosePointsAreBadlyMeasured) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  view.noise_px = 0.2;
  const Pose2D robot{2.1, 2.0, 1.0};
  auto markers = testing::observe(view, robot);
  ASSERT_GE(markers.size(), 5u);
  // Consistent code, but every point of one marker shifted by 8 px.
  for (int k = 0; k < markers[3].point_count; ++k) markers[3].points[k].u_px += 8.0;
  const PoseEstimate est = positioner.solve(markers, PositioningMode::kLeastSquares);
  ASSERT_TRUE(est.valid);
  EXPECT_EQ(est.markers, static_cast<int>(markers.size()) - 1);
  EXPECT_LT(position_error_m(est, robot), 3e-3);
}

TEST(LeastSquares, CovarianceIsPositiveDefinite) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  view.noise_px = 0.3;
  const PoseEstimate est =
      positioner.solve(testing::observe(view, {1.8, 2.2, 0.3}), PositioningMode::kLeastSquares);
  ASSERT_TRUE(est.valid);
  const auto& c = est.covariance;
  // Sylvester: all leading minors positive.
  EXPECT_GT(c[0], 0.0);
  EXPECT_GT(c[0] * c[4] - c[1] * c[3], 0.0);
  const double det = c[0] * (c[4] * c[8] - c[5] * c[7]) - c[1] * (c[3] * c[8] - c[5] * c[6]) +
                     c[2] * (c[3] * c[7] - c[4] * c[6]);
  EXPECT_GT(det, 0.0);
  EXPECT_NEAR(c[1], c[3], 1e-15);
}

TEST(LeastSquares, CovarianceShrinksWithMoreMarkers) {
  PipelineConfig config;
  config.positioning.lsq_sigma_floor_m = 0.0;
  config.positioning.lsq_sigma_floor_yaw_rad = 0.0;
  Positioner positioner(config);
  testing::SyntheticView view;
  view.noise_px = 0.3;
  const Pose2D robot{2.0, 2.0, 0.2};
  auto markers = testing::observe(view, robot);
  ASSERT_GE(markers.size(), 8u);
  const PoseEstimate all = positioner.solve(markers, PositioningMode::kLeastSquares);
  markers.resize(2);
  const PoseEstimate two = positioner.solve(markers, PositioningMode::kLeastSquares);
  ASSERT_TRUE(all.valid);
  ASSERT_TRUE(two.valid);
  EXPECT_LT(all.covariance[0], two.covariance[0]);
  EXPECT_LT(all.covariance[4], two.covariance[4]);
  EXPECT_LT(all.covariance[8], two.covariance[8]);
}

TEST(LeastSquares, CovarianceMatchesScatterOfNoisySolutions) {
  PipelineConfig config;
  config.positioning.lsq_sigma_floor_m = 0.0;
  Positioner positioner(config);
  testing::SyntheticView view;
  view.noise_px = 0.5;
  const Pose2D robot{2.0, 2.0, 0.2};
  double sum_sq = 0.0, sum_var = 0.0;
  const int trials = 60;
  for (int t = 0; t < trials; ++t) {
    view.seed = 100 + t;
    const PoseEstimate est =
        positioner.solve(testing::observe(view, robot), PositioningMode::kLeastSquares);
    ASSERT_TRUE(est.valid);
    sum_sq += (est.pose.x_m - robot.x_m) * (est.pose.x_m - robot.x_m);
    sum_var += est.covariance[0];
  }
  // Reported variance within a factor 2 of the observed scatter.
  const double ratio = sum_sq / sum_var;
  EXPECT_GT(ratio, 0.5);
  EXPECT_LT(ratio, 2.0);
}

TEST(LeastSquares, SingleMarkerHoldsTiltAndStillSolves) {
  PipelineConfig config;
  Positioner positioner(config);
  testing::SyntheticView view;
  const Pose2D robot{2.0, 2.0, 0.5};
  auto markers = testing::observe(view, robot);
  markers.resize(1);
  const PoseEstimate est = positioner.solve(markers, PositioningMode::kLeastSquares);
  ASSERT_TRUE(est.valid);
  EXPECT_EQ(est.markers, 1);
  EXPECT_LT(position_error_m(est, robot), 1e-6);
}

TEST(LeastSquares, RemovesMountOffsetAndYawWithDistortion) {
  PipelineConfig config;
  config.mount.offset_forward_m = 0.2;
  config.mount.offset_left_m = 0.07;
  config.mount.yaw_rad = -1.2;
  config.intrinsics.distortion = {-0.12, 0.03, 0.001, -0.0015, -0.004};
  Positioner positioner(config);
  testing::SyntheticView view;
  view.mount = config.mount;
  view.intrinsics = config.intrinsics;
  const Pose2D robot{1.5, 2.5, 3.0};
  const PoseEstimate est =
      positioner.solve(testing::observe(view, robot), PositioningMode::kLeastSquares);
  ASSERT_TRUE(est.valid);
  EXPECT_LT(position_error_m(est, robot), 1e-5);
  EXPECT_NEAR(wrap_angle_rad(est.pose.yaw_rad - robot.yaw_rad), 0.0, 1e-5);
}

TEST(LeastSquares, EstimatesLensHeightWhenAsked) {
  PipelineConfig config;
  config.mount.lens_height_m = 0.25;  // configured wrong by 5.5 cm
  config.positioning.lsq_estimate_height = true;
  Positioner positioner(config);
  testing::SyntheticView view;  // the true lens height is SPEC's 0.3048 m
  const Pose2D robot{2.0, 2.3, -0.4};
  const PoseEstimate est =
      positioner.solve(testing::observe(view, robot), PositioningMode::kLeastSquares);
  ASSERT_TRUE(est.valid);
  EXPECT_NEAR(positioner.last_lsq().lens_height_m, 0.3048, 1e-4);
  EXPECT_LT(position_error_m(est, robot), 1e-4);
}

// A robot turning on an arc, seen through a 33 ms rolling shutter: its
// velocity turns with it during the readout, 4.5 m/s² at 1.5 m/s and
// 3 rad/s. A velocity held constant in the world left that out, 0.6 mm over
// half the readout, and the fit took it for a tilt of the camera (an unseen
// rolling-shutter drive's frame was 1.5 mm off; docs/decisions.md).
TEST(LeastSquares, ARollingShutterOnAnArcIsModelled) {
  PipelineConfig config;
  config.intrinsics.readout_ms = 33.0;
  testing::SyntheticView view;
  view.intrinsics = config.intrinsics;
  view.forward_mps = 1.5;
  view.noise_px = 0.05;
  for (double yaw_rate_radps : {3.0, -3.0}) {
    view.yaw_rate_radps = yaw_rate_radps;
    for (const Pose2D robot : {Pose2D{2.2, 1.9, 2.8}, Pose2D{1.7, 2.4, -0.9}}) {
      Positioner positioner(config);
      const PoseEstimate est =
          positioner.solve(testing::observe(view, robot), PositioningMode::kLeastSquares);
      ASSERT_TRUE(est.valid);
      const LsqResult& lsq = positioner.last_lsq();
      ASSERT_TRUE(lsq.motion_estimated);
      EXPECT_FALSE(lsq.tilt_estimated) << yaw_rate_radps;
      EXPECT_LT(position_error_m(est, robot), 2.5e-5) << yaw_rate_radps;
      EXPECT_NEAR(lsq.yaw_rate_radps, yaw_rate_radps, 0.05);
      EXPECT_NEAR(lsq.cam_vx_mps, 1.5 * std::cos(robot.yaw_rad), 0.02);
      EXPECT_NEAR(lsq.cam_vy_mps, 1.5 * std::sin(robot.yaw_rad), 0.02);
    }
  }
}

}  // namespace
}  // namespace ceilpose
