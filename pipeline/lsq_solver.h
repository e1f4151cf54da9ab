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
};

// Holds the per-frame work arrays (sized for the largest frame), so solve()
// never allocates. One instance per thread.
class LsqSolver {
 public:
  LsqSolver() = default;

  // `use` flags the markers (indices into fixes) to solve from; markers
  // rejected as outliers are cleared in it. Seeds from the fixes' Change of
  // Axes answers. False when too few points, no convergence or the residual
  // stays above params.lsq_max_rms_px.
  bool solve(const ViewGeometry& view, const PositioningParams& params,
             std::span<const MarkerObservation> markers, std::span<const MarkerFix> fixes,
             std::span<bool> use, LsqResult* out);

 private:
  struct Point {
    double x_n, y_n;  // undistorted normalized observation (camera frame)
    Vec3 world;       // marker point on the ceiling
    int fix;          // index into fixes
  };
  struct State {
    Vec3 t_w;   // optical centre
    Mat3 r_wc;  // camera axes in the world
  };
  static constexpr int kParams = 6;  // tx, ty, yaw, tilt about Xc, tilt about Yc, tz
  using Normal = std::array<double, kParams * kParams>;
  using Vector = std::array<double, kParams>;

  // Weighted normal equations at `state`; returns the robust cost.
  double accumulate(const ViewGeometry& view, const PositioningParams& params,
                    std::span<const bool> use, const State& state, bool with_jacobian, Normal* a,
                    Vector* b, double* sum_w_r2, int* count) const;
  // Squared reprojection residual of one point, pixels².
  static double residual2_px(const ViewGeometry& view, const Mat3& r_cw, const Vec3& t_w,
                             const Point& pt);
  double optimise(const ViewGeometry& view, const PositioningParams& params, std::span<bool> use,
                  std::span<const MarkerFix> fixes, bool reject, State* state, int* marker_count,
                  int* iterations);
  double prior_cost(const ViewGeometry& view, const PositioningParams& params, const State& state,
                    Normal* a, Vector* b) const;
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
};

}  // namespace ceilpose
