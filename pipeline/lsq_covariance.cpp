#include "pipeline/lsq_covariance.h"

#include <algorithm>
#include <cmath>

#include "core/small_matrix.h"

namespace ceilpose {
namespace {
constexpr int kN = kLsqParams;
}  // namespace

// What the markers' placement adds to the covariance. All points of one
// marker move together when the marker is off the spot the map gives it, so
// their errors are not the independent pixel noise that sigma^2 (J^T W J)^-1
// assumes: per marker, B_k = sum w J^T J_m (J_m the residuals' Jacobian with
// respect to the marker's centre and rotation) carries a placement error
// into the normal equations, and M = sum B_k D_k B_k^T is its information
// cost. D_k holds the map's sigmas plus the placement scatter the
// grid-consistent markers show (those the solve rejected included: leaving
// them out would measure only the markers that happen to agree): the shift and turn each marker's
// residuals ask for, pooled over the 2K - 3 (shift) and K - 1 (turn) degrees of freedom the pose
// leaves them (K >= 2 markers).
LsqNormal LsqCovariance::placement_information(
    const ViewGeometry& view, const PositioningParams& params, std::span<const LsqPoint> points,
    std::span<const PointTerms> terms, std::span<const MarkerFix> fixes,
    std::span<const bool> consistent, std::span<const bool> use, const LsqState& st,
    const LsqModel& model) {
  const double k = params.lsq_huber_px;
  // Only the free unknowns' rows: the covariance reads M through
  // (J^T W J)^-1, whose other rows are zero.
  std::array<int, kN> free{};
  const int free_n = model.free_unknowns(&free);
  const PointCamera centre = centre_camera(st);
  const int n_fix = static_cast<int>(fixes.size());
  for (int f = 0; f < n_fix; ++f) marker_terms_[f] = MarkerTerm{};
  for (size_t i = 0; i < points.size(); ++i) {
    const LsqPoint& pt = points[i];
    if (!consistent[pt.fix]) continue;
    double rx = 0.0, ry = 0.0;
    double own_jx[kN], own_jy[kN];
    const double* jx = own_jx;
    const double* jy = own_jy;
    // A point in use: as the fit's last accumulate found it at st (its
    // Jacobian's columns this model leaves out may be filled: only the
    // free unknowns' are read).
    if (!terms.empty() && terms[i].kept) {
      rx = terms[i].rx, ry = terms[i].ry;
      jx = terms[i].jx, jy = terms[i].jy;
    } else {
      const PointCamera cam = point_camera(st, pt, centre, true);
      if (!point_residual(view, pt, cam, &rx, &ry)) continue;
      point_jacobian(view, pt, cam, own_jx, own_jy, model.tilt_free(), model.motion_free());
    }
    const double r = std::sqrt(rx * rx + ry * ry);
    // Markers the solve rejected carry no weight in the pose but are
    // evidence of how far off their places the markers are.
    const double w = !use[pt.fix] ? 0.0 : r <= k ? 1.0 : k / r;
    // A marker shift moves its points as a camera shift the other way; its
    // rotation moves a point at (dx, dy) from the centre by (−dy, dx)·dθ.
    const MarkerFix& fix = fixes[pt.fix];
    const double ox = pt.world[0] - fix.world_x_m, oy = pt.world[1] - fix.world_y_m;
    const double mx[3] = {-jx[kLsqTx], -jx[kLsqTy], jx[kLsqTx] * oy - jx[kLsqTy] * ox};
    const double my[3] = {-jy[kLsqTx], -jy[kLsqTy], jy[kLsqTx] * oy - jy[kLsqTy] * ox};
    MarkerTerm& term = marker_terms_[pt.fix];
    for (int i = 0; i < free_n; ++i) {
      const int r1 = free[i];
      for (int c = 0; c < 3; ++c) term.b[r1 * 3 + c] += w * (jx[r1] * mx[c] + jy[r1] * my[c]);
    }
    for (int r1 = 0; r1 < 3; ++r1) {
      term.jtr[r1] += mx[r1] * rx + my[r1] * ry;
      for (int c = 0; c < 3; ++c) term.jtj[r1 * 3 + c] += mx[r1] * mx[c] + my[r1] * my[c];
    }
    ++term.points;
  }
  // What each marker's residuals say about its own placement error: the
  // least-squares shift and turn of the marker alone that would explain
  // them, (J_m^T J_m)^-1 J_m^T r.
  int markers = 0;
  double shift_m2 = 0.0, turn_rad2 = 0.0;
  for (int f = 0; f < n_fix; ++f) {
    const MarkerTerm& term = marker_terms_[f];
    if (term.points == 0) continue;
    std::array<double, 3> x{};
    if (!solve_spd<3>(term.jtj, {true, true, true}, term.jtr, &x)) continue;
    ++markers;
    shift_m2 += x[0] * x[0] + x[1] * x[1];
    turn_rad2 += x[2] * x[2];
  }
  const double placement_var_m2 = markers >= 2 ? shift_m2 / std::max(1, 2 * markers - 3) : 0.0;
  const double turn_var_rad2 = markers >= 2 ? turn_rad2 / (markers - 1) : 0.0;
  LsqNormal m{};
  for (int f = 0; f < n_fix; ++f) {
    const MarkerTerm& term = marker_terms_[f];
    if (term.points == 0 || !use[f]) continue;
    const MarkerPlacement& pl = *fixes[f].placement;
    const double dk[3] = {pl.sigma_m * pl.sigma_m + placement_var_m2,
                          pl.sigma_m * pl.sigma_m + placement_var_m2,
                          pl.sigma_yaw_rad * pl.sigma_yaw_rad + turn_var_rad2};
    for (int i = 0; i < free_n; ++i)
      for (int j = 0; j < free_n; ++j) {
        const int r1 = free[i], c = free[j];
        double sum = 0.0;
        for (int q = 0; q < 3; ++q) sum += term.b[r1 * 3 + q] * dk[q] * term.b[c * 3 + q];
        m[r1 * kN + c] += sum;
      }
  }
  return m;
}

// Covariance: sigma^2 (J^T W J)^-1 with sigma^2 = sum w r^2 / (m - p) (m
// residual components, p parameters), plus the placement term
// (J^T W J)^-1 M (J^T W J)^-1, marginalised to (t_x, t_y, psi) by taking
// that block, then carried to the robot's (x, y, yaw) through the mount
// offset: x = tx - (f cos yaw - l sin yaw), y = ty - (f sin yaw + l cos yaw);
// plus the configured floors.
bool LsqCovariance::robot_covariance(const ViewGeometry& view, const PositioningParams& params,
                                     const LsqModel& model, std::span<const LsqPoint> points,
                                     std::span<const PointTerms> terms,
                                     std::span<const MarkerFix> fixes,
                                     std::span<const bool> consistent, std::span<const bool> use,
                                     const LsqState& st, const LsqNormal& a, double wr2, int n,
                                     const Pose2D& robot, std::array<double, 9>* out) {
  const LsqNormal placement =
      placement_information(view, params, points, terms, fixes, consistent, use, st, model);
  const double dof = std::max(1, n - model.free_count());
  const double sigma2 = wr2 / dof;
  // g = the first three columns of (J^T W J)^-1.
  std::array<LsqVector, 3> g{};
  for (int c = 0; c < 3; ++c) {
    LsqVector e{};
    e[c] = 1.0;
    if (!solve_spd<kN>(a, model.active, e, &g[c])) return false;
  }
  std::array<double, 9> cam{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      double s = sigma2 * g[c][r];
      for (int i = 0; i < kN; ++i)
        for (int k = 0; k < kN; ++k) s += g[r][i] * placement[i * kN + k] * g[c][k];
      cam[r * 3 + c] = s;
    }
  const double cy = std::cos(robot.yaw_rad), sy = std::sin(robot.yaw_rad);
  const double fwd = view.mount().offset_forward_m, left = view.mount().offset_left_m;
  const double j[9] = {1.0, 0.0, fwd * sy + left * cy, 0.0, 1.0, -(fwd * cy - left * sy), 0.0,
                       0.0, 1.0};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      double s = 0.0;
      for (int k1 = 0; k1 < 3; ++k1)
        for (int k2 = 0; k2 < 3; ++k2) s += j[r * 3 + k1] * cam[k1 * 3 + k2] * j[c * 3 + k2];
      (*out)[r * 3 + c] = s;
    }
  (*out)[0] += params.lsq_sigma_floor_m * params.lsq_sigma_floor_m;
  (*out)[4] += params.lsq_sigma_floor_m * params.lsq_sigma_floor_m;
  (*out)[8] += params.lsq_sigma_floor_yaw_rad * params.lsq_sigma_floor_yaw_rad;
  return true;
}

}  // namespace ceilpose
