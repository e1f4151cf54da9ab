#pragma once
// Least squares over everything seen: the camera's full attitude (position,
// yaw, roll/pitch tilt, optionally height) from every point of every
// consistent marker, by Levenberg–Marquardt on the reprojection error with
// Huber weights, marker-level outlier rejection, and a covariance of the
// robot's (x, y, yaw) from the residuals, the map's sigmas and the scatter
// of the markers about their mapped places.
#include <array>
#include <span>

#include "core/pose.h"
#include "pipeline/change_of_axes.h"
#include "pipeline/marker_observation.h"
#include "pipeline/positioning_params.h"

namespace ceilpose {

struct LsqResult {
  Pose2D robot;
  std::array<double, 9> covariance{};  // (x_m, y_m, yaw_rad), row-major
  double rms_px = 0.0;                 // inliers' RMS reprojection residual
  int markers = 0;                     // markers kept after rejection
  int points = 0;
  int iterations = 0;
  double tilt_x_rad = 0.0;  // estimated camera tilt (core's tilt convention)
  double tilt_y_rad = 0.0;
  double lens_height_m = 0.0;
  bool tilt_estimated = false;  // false: held at the mount's nominal tilt
  // Rolling shutter (camera.readout_ms > 0): the optical centre's velocity
  // and the yaw rate during the readout, world frame, when the markers span
  // enough rows to tell them (motion_estimated); the pose is the centre row's.
  double cam_vx_mps = 0.0;
  double cam_vy_mps = 0.0;
  double yaw_rate_radps = 0.0;
  bool motion_estimated = false;
  bool motion_held = false;  // not estimated: held at the caller's motion
};

// Holds the per-frame work arrays (sized for the largest frame), so solve()
// never allocates. One instance per thread.
class LsqSolver {
 public:
  LsqSolver() = default;

  // `use` flags the markers (indices into fixes) to solve from; markers
  // rejected as outliers are cleared in it. Seeds from the fixes' Change of
  // Axes answers. `motion` (when valid, rolling shutter only) is the prior of
  // the motion during the readout, and its value when the rows cannot tell
  // it. False when too few points, no convergence or the residual stays
  // above params.lsq_max_rms_px.
  bool solve(const ViewGeometry& view, const PositioningParams& params,
             std::span<const MarkerObservation> markers, std::span<const MarkerFix> fixes,
             std::span<bool> use, const CameraMotion& motion, LsqResult* out);

 private:
  struct Point {
    double x_n, y_n;  // undistorted normalized observation (camera frame)
    Vec3 world;       // marker point on the ceiling
    int fix;          // index into fixes
    double tau_s;     // when its row was exposed, after the centre row (rolling shutter)
  };
  struct State {
    Vec3 t_w;                            // optical centre at the centre row's time
    Mat3 r_wc;                           // camera axes in the world, then
    double vx = 0.0, vy = 0.0, w = 0.0;  // optical centre velocity, yaw rate
  };
  // tx, ty, yaw, tilt about Xc, tilt about Yc, tz, and the motion during the
  // readout: vx, vy, yaw rate.
  static constexpr int kParams = 9;
  // The camera when point pt's row was exposed.
  static void camera_at(const State& st, const Point& pt, Vec3* t_w, Mat3* r_wc);
  // What a point's residual and Jacobian need of that camera: Rᵀ, the
  // increment axes (with_axes) and d = P − t. `centre` holds Rᵀ and the axes
  // at the centre row, which a global shutter's points reuse.
  struct PointCamera {
    Vec3 d;
    Mat3 rt;
    std::array<Vec3, 3> axis;
  };
  static PointCamera point_camera(const State& st, const Point& pt, const PointCamera& centre,
                                  bool with_axes);
  using Normal = std::array<double, kParams * kParams>;
  using Vector = std::array<double, kParams>;

  // Weighted normal equations at `state`; returns the robust cost.
  double accumulate(const ViewGeometry& view, const PositioningParams& params,
                    std::span<const bool> use, const State& state, bool with_jacobian, Normal* a,
                    Vector* b, double* sum_w_r2, int* count) const;
  // Squared reprojection residual of one point, pixels².
  static double residual2_px(const ViewGeometry& view, const State& st, const Point& pt);
  double optimise(const ViewGeometry& view, const PositioningParams& params, std::span<bool> use,
                  std::span<const MarkerFix> fixes, bool reject, State* state, int* marker_count,
                  int* iterations);
  double prior_cost(const ViewGeometry& view, const PositioningParams& params, const State& state,
                    Normal* a, Vector* b) const;
  // `st` with the motion it is held at when not estimated.
  State held_motion(const State& st) const;
  // Whether the points span enough rows (and markers) to estimate the motion.
  bool motion_observable(const ViewGeometry& view, std::span<const bool> use,
                         int marker_count) const;
  // The steps of solve(), in order (see lsq_solver.cpp).
  int gather_points(const ViewGeometry& view, std::span<const MarkerObservation> markers,
                    std::span<const MarkerFix> fixes, std::span<const bool> use, State* seed);
  double fit(const ViewGeometry& view, const PositioningParams& params,
             std::span<const MarkerFix> fixes, std::span<bool> use, State* st, int* marker_count,
             int* iterations, bool* tilt_estimated);
  double rms_px(const ViewGeometry& view, std::span<const bool> use, const State& st, int n) const;
  Normal placement_information(const ViewGeometry& view, const PositioningParams& params,
                               std::span<const MarkerFix> fixes, std::span<const bool> consistent,
                               std::span<const bool> use, const State& st);
  bool robot_covariance(const ViewGeometry& view, const PositioningParams& params, const Normal& a,
                        const Normal& placement, double wr2, int n, const Pose2D& robot,
                        std::array<double, 9>* out) const;

  // Per marker: B_k (kParams x 3, row-major), and J_m^T J_m, J_m^T r of its
  // own placement parameters (centre x, y, rotation).
  struct MarkerTerm {
    std::array<double, kParams * 3> b{};
    std::array<double, 9> jtj{};
    std::array<double, 3> jtr{};
    int points = 0;
  };

  std::array<Point, kMaxMarkersPerFrame * kMaxPointsPerMarker> points_{};
  int point_count_ = 0;
  std::array<bool, kParams> active_{};
  std::array<MarkerTerm, kMaxMarkersPerFrame> marker_terms_{};
  CameraMotion motion_;  // this solve's
};

}  // namespace ceilpose
