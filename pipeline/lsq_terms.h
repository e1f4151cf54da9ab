#pragma once
// The least-squares problem's terms: its unknowns, the points it is solved
// from, their pixel residuals and Jacobians, the priors, and the weighted
// normal equations. The solve's steps (lsq_solver.cpp) and the covariance
// (lsq_covariance.cpp) are both written on these. Allocation-free.
//
// Residuals are in pixels, r = f·(observed − projected) in undistorted
// normalized coordinates (core/camera_model.h's normalized_residual_px).
// Unknowns: the optical centre t (x, y, optionally z), a rotation increment
// applied on the left, R ← Exp(ω)·R with ω = δψ·ẑ + δa·Xl + δb·Yl (Xl, Yl
// the level camera's axes: δψ is exactly a yaw change, δa and δb tilt
// changes), with a rolling shutter the optical centre's velocity and the yaw
// rate during the readout, and with edge points the edge offset: how far
// outwards, pixels, every edge's half-way level lies from the edge itself
// (gamma, glare and a lens's blur move the half-way level of a dark-on-light
// step alike on every edge).
#include <array>
#include <span>

#include "core/view_geometry.h"
#include "pipeline/camera_motion.h"
#include "pipeline/positioning_params.h"

namespace ceilpose {

inline constexpr int kLsqParams = 10;
enum LsqParam : int {
  kLsqTx = 0,
  kLsqTy = 1,
  kLsqYaw = 2,
  kLsqTiltX = 3,
  kLsqTiltY = 4,
  kLsqTz = 5,
  kLsqVx = 6,
  kLsqVy = 7,
  kLsqYawRate = 8,
  kLsqEdgeOffset = 9
};
using LsqNormal = std::array<double, kLsqParams * kLsqParams>;
using LsqVector = std::array<double, kLsqParams>;

// One image point and the ceiling point it is of. An edge point (a
// MarkerPointObservation with a normal) has one residual: the pixel
// residual's component along its unit outward normal (normal_x, normal_y),
// less the edge offset; the other component is zero.
struct LsqPoint {
  double x_n, y_n;  // undistorted normalized observation (camera frame)
  Vec3 world;       // marker point on the ceiling
  int fix;          // index into the frame's marker fixes
  double tau_s;     // when its row was exposed, after the centre row (rolling shutter)
  double normal_x = 0.0, normal_y = 0.0;
  bool is_edge() const { return normal_x != 0.0 || normal_y != 0.0; }
  int residuals() const { return is_edge() ? 1 : 2; }
};

// The camera at the centre row's instant, and its motion during the readout.
struct LsqState {
  Vec3 t_w{};                          // optical centre
  Mat3 r_wc{};                         // camera axes in the world
  double vx = 0.0, vy = 0.0, w = 0.0;  // optical centre velocity, yaw rate
  double edge_offset_px = 0.0;         // edge points' outward offset
  // Not an unknown: the weight of an edge point's residual against a
  // centroid's, from their scatter in this frame (lsq_solver.cpp).
  double edge_weight = 1.0;
};

// Which unknowns a fit frees, and the motion it holds them at or draws them
// towards: passed to every step, never kept between solves.
struct LsqModel {
  std::array<bool, kLsqParams> active{};
  CameraMotion motion;  // the caller's (rolling shutter), else invalid
  bool tilt_free() const { return active[kLsqTiltX]; }
  bool motion_free() const { return active[kLsqVx]; }
  int free_count() const;
  // The free unknowns' indices, ascending, in out[0 .. return value).
  int free_unknowns(std::array<int, kLsqParams>* out) const;
};

// What a point's residual and Jacobian need of its camera: Rᵀ, the
// increment axes and d = P − t; and the state's edge offset.
struct PointCamera {
  Vec3 d;
  Mat3 rt;
  std::array<Vec3, 3> axis;
  double edge_offset_px = 0.0;
  double edge_weight = 1.0;
  double vx_mps = 0.0, vy_mps = 0.0, w_radps = 0.0;  // the motion, for the arc's Jacobian
};

// The camera at the centre row: Rᵀ and the world directions of the yaw and
// the two tilt increments (the vertical and the level camera's axes).
PointCamera centre_camera(const LsqState& st);

// The camera when `pt`'s row was exposed; a global shutter's points reuse
// `centre` (with_axes: also the increment axes, for the Jacobian).
PointCamera point_camera(const LsqState& st, const LsqPoint& pt, const PointCamera& centre,
                         bool with_axes);

// The pixel residual (rx, ry) of `pt` seen by `cam`; false when the point is
// behind the camera (the solve diverged).
bool point_residual(const ViewGeometry& view, const LsqPoint& pt, const PointCamera& cam,
                    double* rx, double* ry);

// Jacobian of the pixel residual with respect to every unknown (LsqParam
// order); without with_tilt the two tilt columns, without with_motion the
// three motion columns are left zero (a fit that holds them, most fits,
// never reads them).
void point_jacobian(const ViewGeometry& view, const LsqPoint& pt, const PointCamera& cam,
                    double* jx, double* jy, bool with_tilt = true, bool with_motion = true);

// Squared reprojection residual of one point, pixels².
double residual2_px(const ViewGeometry& view, const LsqState& st, const LsqPoint& pt);

// A point's residual and Jacobian as accumulate found them at a state, for
// the covariance at the same state to read rather than compute again (a
// tracked 640x480 frame's ~65 points: ~20 k instructions). `kept` false:
// the point's marker was not in use, nothing stored.
struct PointTerms {
  bool kept = false;
  double rx = 0.0, ry = 0.0;
  double jx[kLsqParams], jy[kLsqParams];
};

// Huber-weighted normal equations (with_jacobian; the rows and columns of
// the model's free unknowns, the rest zero) and the robust cost of the
// points whose marker is in use; infinite when a point is behind the
// camera. *sum_w_r2 and *residuals: the weighted squared residuals and how
// many residuals there are (two a point, one an edge point). `terms`,
// unless empty (else at least one per point): each point's PointTerms, with
// the Jacobian.
double accumulate(const ViewGeometry& view, const PositioningParams& params,
                  std::span<const LsqPoint> points, std::span<const bool> use, const LsqState& st,
                  const LsqModel& model, bool with_jacobian, LsqNormal* a, LsqVector* b,
                  double* sum_w_r2, int* residuals, std::span<PointTerms> terms = {});

// The priors' cost, added to the normal equations when `a` is given: the
// motion towards the caller's (or rest), the tilt towards the mount's.
double prior_cost(const ViewGeometry& view, const PositioningParams& params, const LsqModel& model,
                  const LsqState& st, LsqNormal* a, LsqVector* b);

// The tilt's prior alone (prior_cost's second part): `cost` plus its cost,
// its terms added to the normal equations when `a` is given.
double add_tilt_prior(const ViewGeometry& view, const PositioningParams& params, const LsqState& st,
                      double cost, LsqNormal* a, LsqVector* b);

// `st` with the motion it is held at when the fit does not estimate it.
LsqState held_motion(const LsqModel& model, const LsqState& st);

// The state moved by a step of the unknowns.
LsqState stepped(const LsqState& st, const LsqVector& step);

}  // namespace ceilpose
