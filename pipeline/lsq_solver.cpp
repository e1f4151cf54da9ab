#include "pipeline/lsq_solver.h"

#include <algorithm>
#include <cmath>

namespace ceilpose {
namespace {

constexpr int kN = 9;
enum Param : int {
  kTx = 0,
  kTy = 1,
  kYaw = 2,
  kTiltX = 3,
  kTiltY = 4,
  kTz = 5,
  kVx = 6,
  kVy = 7,
  kYawRate = 8
};
// The motion is estimated only from markers spread over at least this share
// of the readout's rows, and at least this many of them; otherwise it is held
// (at the filter's motion when the caller gives it, else at rest). Its prior
// is the caller's motion, or rest with 1 m/s and 3 rad/s per pixel of
// residual, which only conditions the solve when the rows barely tell it.
// The caller's sigmas are floored: a filter that has just missed a turn must
// not override what the rows say.
constexpr double kMotionMinRowSpan = 0.3;
constexpr int kMotionMinMarkers = 3;
constexpr double kMotionPriorMps = 1.0;
constexpr double kMotionPriorRadps = 3.0;
constexpr double kMotionPriorFloorMps = 0.05;
constexpr double kMotionPriorFloorRadps = 0.2;
// Marker-level rejection passes after the first solve.
constexpr int kMaxRejections = 3;

// Level camera axes for camera yaw psi (SPEC §3), row-major.
Mat3 level_rotation(double psi) {
  const double s = std::sin(psi), c = std::cos(psi);
  return {-s, -c, 0.0, c, -s, 0.0, 0.0, 0.0, 1.0};
}

// Camera yaw of a possibly tilted camera: R = Level(ψ)·Rx(a)·Ry(b) has
// Yc = (−cos a·cosψ, −cos a·sinψ, sin a), so ψ is the floor heading of −Yc
// (image up), exact for any tilt below 90°.
double camera_yaw(const Mat3& r) { return std::atan2(-r[4], -r[1]); }

// Tilt (a, b) of R = Level(ψ)·Rx(a)·Ry(b): M = Level(ψ)ᵀR = Rx(a)Ry(b) =
// [[cb, 0, sb], [sa·sb, ca, −sa·cb], [−ca·sb, sa, ca·cb]].
void camera_tilt(const Mat3& r, double* a, double* b) {
  const Mat3 m = mat_mul(mat_transpose(level_rotation(camera_yaw(r))), r);
  *a = std::atan2(-m[5], m[8]);
  *b = std::asin(std::clamp(m[2], -1.0, 1.0));
}

// Rotation by the vector w (Rodrigues).
Mat3 exp_so3(const Vec3& w) {
  const double theta = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  if (theta < 1e-12) return {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const double kx = w[0] / theta, ky = w[1] / theta, kz = w[2] / theta;
  const double c = std::cos(theta), s = std::sin(theta), v = 1.0 - c;
  return {kx * kx * v + c,      kx * ky * v - kz * s, kx * kz * v + ky * s,
          kx * ky * v + kz * s, ky * ky * v + c,      ky * kz * v - kx * s,
          kx * kz * v - ky * s, ky * kz * v + kx * s, kz * kz * v + c};
}

// Cholesky solve of the active block of a symmetric positive definite
// system in place; inactive parameters get 0. False when not SPD.
bool solve_spd(std::array<double, kN * kN> a, const std::array<bool, kN>& active,
               std::array<double, kN> b, std::array<double, kN>* x) {
  for (int i = 0; i < kN; ++i) {
    if (active[i]) continue;
    for (int j = 0; j < kN; ++j) a[i * kN + j] = a[j * kN + i] = 0.0;
    a[i * kN + i] = 1.0;
    b[i] = 0.0;
  }
  for (int j = 0; j < kN; ++j) {
    double d = a[j * kN + j];
    for (int k = 0; k < j; ++k) d -= a[j * kN + k] * a[j * kN + k];
    if (!(d > 0.0)) return false;
    d = std::sqrt(d);
    a[j * kN + j] = d;
    for (int i = j + 1; i < kN; ++i) {
      double s = a[i * kN + j];
      for (int k = 0; k < j; ++k) s -= a[i * kN + k] * a[j * kN + k];
      a[i * kN + j] = s / d;
    }
  }
  for (int i = 0; i < kN; ++i) {
    double s = b[i];
    for (int k = 0; k < i; ++k) s -= a[i * kN + k] * b[k];
    b[i] = s / a[i * kN + i];
  }
  for (int i = kN - 1; i >= 0; --i) {
    double s = b[i];
    for (int k = i + 1; k < kN; ++k) s -= a[k * kN + i] * b[k];
    b[i] = s / a[i * kN + i];
  }
  *x = b;
  return true;
}

// World directions of the yaw and the two tilt increments at attitude r_wc:
// the vertical and the level camera's axes.
std::array<Vec3, 3> increment_axes(const Mat3& r_wc) {
  const Mat3 lev = level_rotation(camera_yaw(r_wc));
  return {{{0.0, 0.0, 1.0}, {lev[0], lev[3], lev[6]}, {lev[1], lev[4], lev[7]}}};
}

// Jacobian of one point's pixel residual r = f·(observed − projected) with
// respect to the parameters (Param order), for the ceiling point at d = P − t
// in the world and p = Rᵀd in the camera; `axis` holds the world directions
// of the yaw and the two tilt increments.
void point_jacobian(double fx, double fy, const Mat3& rt, const std::array<Vec3, 3>& axis,
                    const Vec3& d, const Vec3& p, double* jx, double* jy) {
  const double iz = 1.0 / p[2];
  double dp[3][kN] = {};
  for (int row = 0; row < 3; ++row) {
    dp[row][kTx] = -rt[row * 3 + 0];
    dp[row][kTy] = -rt[row * 3 + 1];
    dp[row][kTz] = -rt[row * 3 + 2];
  }
  const int rot_cols[3] = {kYaw, kTiltX, kTiltY};
  for (int c = 0; c < 3; ++c) {
    const Vec3& w3 = axis[c];
    const Vec3 cross{d[1] * w3[2] - d[2] * w3[1], d[2] * w3[0] - d[0] * w3[2],
                     d[0] * w3[1] - d[1] * w3[0]};  // [a]×·w = a × w
    const Vec3 col = mat_vec(rt, cross);
    for (int row = 0; row < 3; ++row) dp[row][rot_cols[c]] = col[row];
  }
  for (int c = 0; c < kVx; ++c) {
    // ∂r/∂param = −f·∂(projection)/∂param
    jx[c] = -fx * iz * (dp[0][c] - p[0] * iz * dp[2][c]);
    jy[c] = -fy * iz * (dp[1][c] - p[1] * iz * dp[2][c]);
  }
}

// The motion's columns for a point exposed tau seconds after the centre row:
// its camera is t + v·tau and Exp(w·tau·z)·R, so moving v or w moves it as
// moving t or the yaw by tau times as much.
void motion_jacobian(double tau_s, double* jx, double* jy) {
  jx[kVx] = tau_s * jx[kTx];
  jx[kVy] = tau_s * jx[kTy];
  jx[kYawRate] = tau_s * jx[kYaw];
  jy[kVx] = tau_s * jy[kTx];
  jy[kVy] = tau_s * jy[kTy];
  jy[kYawRate] = tau_s * jy[kYaw];
}

// Rotation by angle a about the world's vertical, applied on the left.
Mat3 turned(const Mat3& r, double a) {
  const double s = std::sin(a), c = std::cos(a);
  return mat_mul({c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0}, r);
}

}  // namespace

void LsqSolver::camera_at(const State& st, const Point& pt, Vec3* t_w, Mat3* r_wc) {
  if (pt.tau_s == 0.0) {  // global shutter: no arithmetic, the same bits
    *t_w = st.t_w;
    *r_wc = st.r_wc;
    return;
  }
  *t_w = {st.t_w[0] + st.vx * pt.tau_s, st.t_w[1] + st.vy * pt.tau_s, st.t_w[2]};
  *r_wc = turned(st.r_wc, st.w * pt.tau_s);
}

LsqSolver::PointCamera LsqSolver::point_camera(const State& st, const Point& pt,
                                               const PointCamera& centre, bool with_axes) {
  PointCamera cam = centre;
  Vec3 t_w = st.t_w;
  if (pt.tau_s != 0.0) {
    Mat3 r_wc;
    camera_at(st, pt, &t_w, &r_wc);
    cam.rt = mat_transpose(r_wc);
    if (with_axes) {
      // The turn about the vertical turns the level axes with it; the yaw
      // axis stays vertical.
      const double a = st.w * pt.tau_s, sa = std::sin(a), ca = std::cos(a);
      for (int k = 1; k < 3; ++k) {
        const Vec3 l = centre.axis[k];
        cam.axis[k] = {ca * l[0] - sa * l[1], sa * l[0] + ca * l[1], l[2]};
      }
    }
  }
  cam.d = {pt.world[0] - t_w[0], pt.world[1] - t_w[1], pt.world[2] - t_w[2]};
  return cam;
}

double LsqSolver::residual2_px(const ViewGeometry& view, const State& st, const Point& pt) {
  Vec3 t_w;
  Mat3 r_wc;
  camera_at(st, pt, &t_w, &r_wc);
  const Vec3 p = mat_vec(mat_transpose(r_wc),
                         {pt.world[0] - t_w[0], pt.world[1] - t_w[1], pt.world[2] - t_w[2]});
  const double rx = view.intrinsics().fx * (pt.x_n - p[0] / p[2]);
  const double ry = view.intrinsics().fy * (pt.y_n - p[1] / p[2]);
  return rx * rx + ry * ry;
}

// Residuals are in pixels: r = f·(observed − projected) in undistorted
// normalized coordinates (undistorting the observations once is cheaper than
// distorting every projection and differentiates more simply).
//
// Parameters: the optical centre t (x, y, and optionally z) and a rotation
// increment applied on the left, R ← Exp(ω)·R, with ω = δψ·ẑ + δa·Xl + δb·Yl
// (Xl, Yl the level camera's axes): δψ is exactly a yaw change and δa, δb
// are tilt changes about the level axes. For a ceiling point P, a = P − t,
// p = Rᵀa:  ∂p/∂t = −Rᵀ,  ∂p/∂ω = Rᵀ[a]×,  and x = X/Z, y = Y/Z give
// ∂x/∂p = (1/Z, 0, −X/Z²), ∂y/∂p = (0, 1/Z, −Y/Z²).
double LsqSolver::accumulate(const ViewGeometry& view, const PositioningParams& params,
                             std::span<const bool> use, const State& st, bool with_jacobian,
                             Normal* a, Vector* b, double* sum_w_r2, int* count) const {
  const double fx = view.intrinsics().fx, fy = view.intrinsics().fy;
  const double k = params.lsq_huber_px;
  const PointCamera centre{{}, mat_transpose(st.r_wc), increment_axes(st.r_wc)};
  if (with_jacobian) {
    a->fill(0.0);
    b->fill(0.0);
  }
  double cost = 0.0, wr2 = 0.0;
  int n = 0;
  for (int i = 0; i < point_count_; ++i) {
    const Point& pt = points_[i];
    if (!use[pt.fix]) continue;
    const PointCamera cam = point_camera(st, pt, centre, with_jacobian);
    const Vec3& d = cam.d;
    const Vec3 p = mat_vec(cam.rt, d);
    if (p[2] < 1e-3) return INFINITY;  // a point behind the camera: diverged
    const double iz = 1.0 / p[2];
    const double rx = fx * (pt.x_n - p[0] * iz), ry = fy * (pt.y_n - p[1] * iz);
    const double r = std::sqrt(rx * rx + ry * ry);
    const double w = r <= k ? 1.0 : k / r;
    cost += r <= k ? r * r : 2.0 * k * r - k * k;
    wr2 += w * r * r;
    ++n;
    if (!with_jacobian) continue;
    double jx[kN], jy[kN];
    point_jacobian(fx, fy, cam.rt, cam.axis, d, p, jx, jy);
    motion_jacobian(pt.tau_s, jx, jy);
    for (int r1 = 0; r1 < kN; ++r1) {
      (*b)[r1] -= w * (jx[r1] * rx + jy[r1] * ry);
      for (int c = r1; c < kN; ++c) (*a)[r1 * kN + c] += w * (jx[r1] * jx[c] + jy[r1] * jy[c]);
    }
  }
  if (with_jacobian) {
    for (int r1 = 0; r1 < kN; ++r1)
      for (int c = 0; c < r1; ++c) (*a)[r1 * kN + c] = (*a)[c * kN + r1];
  }
  *sum_w_r2 = wr2;
  *count = n;
  return cost;
}

// A soft prior keeps the tilt near the mount's nominal tilt when the points
// cannot separate it from translation (few, clustered markers); its weight
// is that of one 1-pixel residual per lsq_tilt_prior_rad.
double LsqSolver::prior_cost(const ViewGeometry& view, const PositioningParams& params,
                             const State& st, Normal* a, Vector* b) const {
  double motion = 0.0;
  if (active_[kVx]) {
    const double wv = 1.0 / (motion_.valid ? std::max(motion_.sigma_v_mps, kMotionPriorFloorMps)
                                           : kMotionPriorMps);
    const double ww =
        1.0 / (motion_.valid ? std::max(motion_.sigma_yaw_rate_radps, kMotionPriorFloorRadps)
                             : kMotionPriorRadps);
    const State held = held_motion(st);
    const double r[3] = {wv * (st.vx - held.vx), wv * (st.vy - held.vy), ww * (st.w - held.w)};
    const double wt[3] = {wv, wv, ww};
    for (int k = 0; k < 3; ++k) {
      motion += r[k] * r[k];
      if (a == nullptr) continue;
      (*a)[(kVx + k) * kN + kVx + k] += wt[k] * wt[k];
      (*b)[kVx + k] -= wt[k] * r[k];
    }
  }
  if (!active_[kTiltX]) return motion;
  double ta = 0.0, tb = 0.0;
  camera_tilt(st.r_wc, &ta, &tb);
  const double w = 1.0 / params.lsq_tilt_prior_rad;
  const double ra = w * (ta - view.mount().tilt_x_rad), rb = w * (tb - view.mount().tilt_y_rad);
  if (a != nullptr) {
    (*a)[kTiltX * kN + kTiltX] += w * w;
    (*a)[kTiltY * kN + kTiltY] += w * w;
    (*b)[kTiltX] -= w * ra;
    (*b)[kTiltY] -= w * rb;
  }
  return motion + ra * ra + rb * rb;
}

LsqSolver::State LsqSolver::held_motion(const State& st) const {
  State out = st;
  out.vx = motion_.valid ? motion_.vx_mps : 0.0;
  out.vy = motion_.valid ? motion_.vy_mps : 0.0;
  out.w = motion_.valid ? motion_.yaw_rate_radps : 0.0;
  return out;
}

bool LsqSolver::motion_observable(const ViewGeometry& view, std::span<const bool> use,
                                  int marker_count) const {
  const double readout_s = view.intrinsics().readout_ms * 1e-3;
  if (!(readout_s > 0.0) || marker_count < kMotionMinMarkers) return false;
  double lo = INFINITY, hi = -INFINITY;
  for (int i = 0; i < point_count_; ++i) {
    if (!use[points_[i].fix]) continue;
    lo = std::min(lo, points_[i].tau_s);
    hi = std::max(hi, points_[i].tau_s);
  }
  return hi - lo >= kMotionMinRowSpan * readout_s;
}

// Levenberg–Marquardt with Huber weights (IRLS) over the active
// parameters; with `reject`, then drops the worst marker if its RMS residual
// exceeds lsq_marker_reject_px and solves again from where it is. Returns
// the robust cost (infinite if the solve diverged).
double LsqSolver::optimise(const ViewGeometry& view, const PositioningParams& params,
                           std::span<bool> use, std::span<const MarkerFix> fixes, bool reject,
                           State* state, int* marker_count, int* iterations) {
  State& st = *state;
  Normal a{};
  Vector b{};
  double wr2 = 0.0, cost = INFINITY;
  int n = 0;
  for (int pass = 0; pass <= kMaxRejections; ++pass) {
    double lambda = 1e-4;
    cost = accumulate(view, params, use, st, true, &a, &b, &wr2, &n) +
           prior_cost(view, params, st, &a, &b);
    if (!std::isfinite(cost)) return INFINITY;
    for (int it = 0; it < params.lsq_max_iterations; ++it, ++*iterations) {
      Normal damped = a;
      for (int i = 0; i < kN; ++i) damped[i * kN + i] *= 1.0 + lambda;
      Vector step{};
      if (!solve_spd(damped, active_, b, &step)) return INFINITY;
      State trial = st;
      trial.t_w[0] += step[kTx];
      trial.t_w[1] += step[kTy];
      trial.t_w[2] += step[kTz];
      const Mat3 lev = level_rotation(camera_yaw(st.r_wc));
      Vec3 w{0.0, 0.0, step[kYaw]};
      for (int r = 0; r < 3; ++r) w[r] += step[kTiltX] * lev[r * 3] + step[kTiltY] * lev[r * 3 + 1];
      trial.r_wc = mat_mul(exp_so3(w), st.r_wc);
      trial.vx += step[kVx];
      trial.vy += step[kVy];
      trial.w += step[kYawRate];
      Normal ta{};
      Vector tb{};
      double twr2 = 0.0;
      int tn = 0;
      const double trial_cost = accumulate(view, params, use, trial, true, &ta, &tb, &twr2, &tn) +
                                prior_cost(view, params, trial, &ta, &tb);
      if (trial_cost <= cost) {
        st = trial;
        cost = trial_cost;
        a = ta;
        b = tb;
        lambda = std::max(lambda * 0.1, 1e-9);
        double step_norm = 0.0;
        for (double v : step) step_norm = std::max(step_norm, std::abs(v));
        if (step_norm < params.lsq_step_tolerance) break;
      } else {
        lambda *= 10.0;
        if (lambda > 1e6) break;
      }
    }
    if (!reject || *marker_count <= 1 || pass == kMaxRejections) break;
    // Per-marker RMS residual; the worst offender is dropped if too large.
    int worst = -1;
    double worst_rms2 = params.lsq_marker_reject_px * params.lsq_marker_reject_px;
    for (int f = 0; f < static_cast<int>(fixes.size()); ++f) {
      if (!use[f]) continue;
      double sum = 0.0;
      int cnt = 0;
      for (int i = 0; i < point_count_; ++i) {
        const Point& pt = points_[i];
        if (pt.fix != f) continue;
        sum += residual2_px(view, st, pt);
        ++cnt;
      }
      if (cnt > 0 && sum / cnt > worst_rms2) {
        worst_rms2 = sum / cnt;
        worst = f;
      }
    }
    if (worst < 0) break;
    use[worst] = false;
    --*marker_count;
    if (*marker_count < params.lsq_tilt_min_markers) active_[kTiltX] = active_[kTiltY] = false;
    if (active_[kVx] && !motion_observable(view, use, *marker_count)) {
      active_[kVx] = active_[kVy] = active_[kYawRate] = false;
      st = held_motion(st);
    }
  }
  return cost;
}

// 1. Correspondences of the markers in use (a marker without measured points
// still gives its centre and its two rectangle centres), and the seed: the
// Change of Axes answers averaged, nominal tilt and height. Returns the
// markers used.
int LsqSolver::gather_points(const ViewGeometry& view, std::span<const MarkerObservation> markers,
                             std::span<const MarkerFix> fixes, std::span<const bool> use,
                             State* seed) {
  const CeilingLayout& layout = view.layout();
  const CameraIntrinsics& k = view.intrinsics();
  point_count_ = 0;
  int marker_count = 0;
  double sin_sum = 0.0, cos_sum = 0.0, x_sum = 0.0, y_sum = 0.0;
  for (int f = 0; f < static_cast<int>(fixes.size()); ++f) {
    if (!use[f]) continue;
    const MarkerFix& fix = fixes[f];
    const MarkerObservation& m = markers[fix.index];
    auto add = [&](double e_m, double n_m, double u_px, double v_px) {
      if (point_count_ >= static_cast<int>(points_.size())) return;
      if (!std::isfinite(u_px) || !std::isfinite(v_px) || !std::isfinite(e_m) ||
          !std::isfinite(n_m)) {
        return;
      }
      Point& p = points_[point_count_++];
      undistort_pixel(view.intrinsics(), u_px, v_px, &p.x_n, &p.y_n);
      p.tau_s = row_time_s(k, v_px);
      double x_m = 0.0, y_m = 0.0;
      fix.placement->world_point(e_m, n_m, &x_m, &y_m);
      p.world = {x_m, y_m, layout.height_m};
      p.fix = f;
    };
    if (m.point_count > 0) {
      for (int k = 0; k < std::min(m.point_count, kMaxPointsPerMarker); ++k) {
        add(m.points[k].e_m, m.points[k].n_m, m.points[k].u_px, m.points[k].v_px);
      }
    } else {
      add(0.0, 0.0, m.centre_u_px, m.centre_v_px);
      add(layout.red_centre_e_m(), 0.0, m.red_u_px, m.red_v_px);
      add(layout.green_centre_e_m(), 0.0, m.green_u_px, m.green_v_px);
    }
    ++marker_count;
    sin_sum += std::sin(fix.cam_yaw_rad);
    cos_sum += std::cos(fix.cam_yaw_rad);
    x_sum += fix.cam_x_m;
    y_sum += fix.cam_y_m;
  }
  if (marker_count > 0) {
    seed->t_w = {x_sum / marker_count, y_sum / marker_count, view.mount().lens_height_m};
    seed->r_wc = mat_mul(level_rotation(std::atan2(sin_sum, cos_sum)), view.tilt());
    *seed = held_motion(*seed);
  }
  return marker_count;
}

// 2. Free tilt and held tilt, each from the seed with its own marker
// rejection. The held model wins unless the free one keeps as many markers,
// finds a tilt a real mount can have, and explains the points significantly
// better: tilt trades off against translation so closely that estimating it
// costs ~10x the position noise of holding it, a tilt too small to be
// detected is also too small to matter, and on a ceiling whose markers are a
// little off their places a free tilt "explains" the offsets by rejecting a
// good marker and moving the pose by decimetres. Returns the cost (not
// finite: no solution); *tilt_estimated says which model won.
double LsqSolver::fit(const ViewGeometry& view, const PositioningParams& params,
                      std::span<const MarkerFix> fixes, std::span<bool> use, State* st,
                      int* marker_count, int* iterations, bool* tilt_estimated) {
  const bool motion = motion_observable(view, use, *marker_count);
  active_ = {true, true, true, false, false, params.lsq_estimate_height, motion, motion, motion};
  *tilt_estimated = false;
  const bool tilt_allowed =
      params.lsq_estimate_tilt && *marker_count >= params.lsq_tilt_min_markers;
  if (!tilt_allowed) return optimise(view, params, use, fixes, true, st, marker_count, iterations);
  const State seed = *st;
  std::array<bool, kMaxMarkersPerFrame> held_use{};
  std::copy(use.begin(), use.end(), held_use.begin());
  const std::span<bool> held_span(held_use.data(), use.size());
  int held_markers = *marker_count;
  State held = seed;
  const double held_cost =
      optimise(view, params, held_span, fixes, true, &held, &held_markers, iterations);

  active_[kTiltX] = active_[kTiltY] = true;
  double cost = optimise(view, params, use, fixes, true, st, marker_count, iterations);
  double ta = 0.0, tb = 0.0;
  camera_tilt(st->r_wc, &ta, &tb);
  bool free_wins = std::isfinite(cost) && active_[kTiltX] && *marker_count >= held_markers &&
                   std::hypot(ta - view.mount().tilt_x_rad, tb - view.mount().tilt_y_rad) <=
                       params.lsq_max_tilt_rad;
  if (free_wins && std::isfinite(held_cost)) {
    Normal a{};
    Vector b{};
    double wr2 = 0.0;
    int n = 0;
    accumulate(view, params, use, *st, false, &a, &b, &wr2, &n);
    const double sigma2 = cost / std::max(1, 2 * n - 5);
    free_wins = held_cost - cost > params.lsq_tilt_select_chi2 * sigma2;
  }
  if (!free_wins) {
    active_[kTiltX] = active_[kTiltY] = false;
    *st = held;
    std::copy(held_use.begin(), held_use.begin() + static_cast<ptrdiff_t>(use.size()), use.begin());
    *marker_count = held_markers;
    return held_cost;
  }
  *tilt_estimated = true;
  return cost;
}

// 3. RMS reprojection residual of the points in use, pixels.
double LsqSolver::rms_px(const ViewGeometry& view, std::span<const bool> use, const State& st,
                         int n) const {
  double sum_r2 = 0.0;
  for (int i = 0; i < point_count_; ++i) {
    const Point& pt = points_[i];
    if (!use[pt.fix]) continue;
    sum_r2 += residual2_px(view, st, pt);
  }
  return std::sqrt(sum_r2 / n);
}

// 4. What the markers' placement adds to the covariance. All points of one
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
LsqSolver::Normal LsqSolver::placement_information(const ViewGeometry& view,
                                                   const PositioningParams& params,
                                                   std::span<const MarkerFix> fixes,
                                                   std::span<const bool> consistent,
                                                   std::span<const bool> use, const State& st) {
  const double fx = view.intrinsics().fx, fy = view.intrinsics().fy;
  const double k = params.lsq_huber_px;
  const PointCamera centre{{}, mat_transpose(st.r_wc), increment_axes(st.r_wc)};
  const int n_fix = static_cast<int>(fixes.size());
  for (int f = 0; f < n_fix; ++f) marker_terms_[f] = MarkerTerm{};
  for (int i = 0; i < point_count_; ++i) {
    const Point& pt = points_[i];
    if (!consistent[pt.fix]) continue;
    const PointCamera cam = point_camera(st, pt, centre, true);
    const Vec3& d = cam.d;
    const Vec3 p = mat_vec(cam.rt, d);
    if (p[2] < 1e-3) continue;
    const double iz = 1.0 / p[2];
    const double rx = fx * (pt.x_n - p[0] * iz), ry = fy * (pt.y_n - p[1] * iz);
    const double r = std::sqrt(rx * rx + ry * ry);
    // Markers the solve rejected carry no weight in the pose but are
    // evidence of how far off their places the markers are.
    const double w = !use[pt.fix] ? 0.0 : r <= k ? 1.0 : k / r;
    double jx[kN], jy[kN];
    point_jacobian(fx, fy, cam.rt, cam.axis, d, p, jx, jy);
    motion_jacobian(pt.tau_s, jx, jy);
    // A marker shift moves its points as a camera shift the other way; its
    // rotation moves a point at (dx, dy) from the centre by (−dy, dx)·dθ.
    const MarkerFix& fix = fixes[pt.fix];
    const double ox = pt.world[0] - fix.world_x_m, oy = pt.world[1] - fix.world_y_m;
    const double mx[3] = {-jx[kTx], -jx[kTy], jx[kTx] * oy - jx[kTy] * ox};
    const double my[3] = {-jy[kTx], -jy[kTy], jy[kTx] * oy - jy[kTy] * ox};
    MarkerTerm& term = marker_terms_[pt.fix];
    for (int r1 = 0; r1 < kN; ++r1)
      for (int c = 0; c < 3; ++c) term.b[r1 * 3 + c] += w * (jx[r1] * mx[c] + jy[r1] * my[c]);
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
    std::array<double, kN * kN> a{};
    Vector b{}, x{};
    for (int r1 = 0; r1 < 3; ++r1) {
      b[r1] = term.jtr[r1];
      for (int c = 0; c < 3; ++c) a[r1 * kN + c] = term.jtj[r1 * 3 + c];
    }
    const std::array<bool, kN> three{true, true, true, false, false, false, false, false, false};
    if (!solve_spd(a, three, b, &x)) continue;
    ++markers;
    shift_m2 += x[0] * x[0] + x[1] * x[1];
    turn_rad2 += x[2] * x[2];
  }
  const double placement_var_m2 = markers >= 2 ? shift_m2 / std::max(1, 2 * markers - 3) : 0.0;
  const double turn_var_rad2 = markers >= 2 ? turn_rad2 / (markers - 1) : 0.0;
  Normal m{};
  for (int f = 0; f < n_fix; ++f) {
    const MarkerTerm& term = marker_terms_[f];
    if (term.points == 0 || !use[f]) continue;
    const MarkerPlacement& pl = *fixes[f].placement;
    const double dk[3] = {pl.sigma_m * pl.sigma_m + placement_var_m2,
                          pl.sigma_m * pl.sigma_m + placement_var_m2,
                          pl.sigma_yaw_rad * pl.sigma_yaw_rad + turn_var_rad2};
    for (int r1 = 0; r1 < kN; ++r1)
      for (int c = 0; c < kN; ++c) {
        double sum = 0.0;
        for (int q = 0; q < 3; ++q) sum += term.b[r1 * 3 + q] * dk[q] * term.b[c * 3 + q];
        m[r1 * kN + c] += sum;
      }
  }
  return m;
}

// 5. Covariance: sigma^2 (J^T W J)^-1 with sigma^2 = sum w r^2 / (m - p) (m
// residual components, p parameters), plus the placement term
// (J^T W J)^-1 M (J^T W J)^-1, marginalised to (t_x, t_y, psi) by taking
// that block, then carried to the robot's (x, y, yaw) through the mount
// offset: x = tx - (f cos yaw - l sin yaw), y = ty - (f sin yaw + l cos yaw);
// plus the configured floors.
bool LsqSolver::robot_covariance(const ViewGeometry& view, const PositioningParams& params,
                                 const Normal& a, const Normal& placement, double wr2, int n,
                                 const Pose2D& robot, std::array<double, 9>* out) const {
  int p_count = 0;
  for (bool act : active_) p_count += act ? 1 : 0;
  const double dof = std::max(1, 2 * n - p_count);
  const double sigma2 = wr2 / dof;
  // g = the first three columns of (J^T W J)^-1.
  std::array<Vector, 3> g{};
  for (int c = 0; c < 3; ++c) {
    Vector e{};
    e[c] = 1.0;
    if (!solve_spd(a, active_, e, &g[c])) return false;
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

bool LsqSolver::solve(const ViewGeometry& view, const PositioningParams& params,
                      std::span<const MarkerObservation> markers, std::span<const MarkerFix> fixes,
                      std::span<bool> use, const CameraMotion& motion, LsqResult* out) {
  // A global shutter has no motion within the frame to hold or estimate.
  motion_ = view.intrinsics().readout_ms > 0.0 ? motion : CameraMotion{};
  State st;
  std::array<bool, kMaxMarkersPerFrame> consistent{};
  std::copy(use.begin(), use.end(), consistent.begin());
  int marker_count = gather_points(view, markers, fixes, use, &st);
  if (marker_count == 0 || point_count_ < params.lsq_min_points) return false;
  int iterations = 0;
  bool tilt_estimated = false;
  const double cost =
      fit(view, params, fixes, use, &st, &marker_count, &iterations, &tilt_estimated);
  if (!std::isfinite(cost)) return false;
  Normal a{};
  Vector b{};
  double wr2 = 0.0;
  int n = 0;
  accumulate(view, params, use, st, true, &a, &b, &wr2, &n);
  prior_cost(view, params, st, &a, &b);

  // Accept only a solution that explains the points.
  if (n < params.lsq_min_points) return false;
  const double rms = rms_px(view, use, st, n);
  if (!(rms <= params.lsq_max_rms_px)) return false;

  out->robot = view.robot_from_camera(st.t_w[0], st.t_w[1], camera_yaw(st.r_wc));
  const Normal placement = placement_information(
      view, params, fixes, std::span<const bool>(consistent.data(), use.size()), use, st);
  if (!robot_covariance(view, params, a, placement, wr2, n, out->robot, &out->covariance))
    return false;
  out->rms_px = rms;
  out->markers = marker_count;
  out->points = n;
  out->iterations = iterations;
  camera_tilt(st.r_wc, &out->tilt_x_rad, &out->tilt_y_rad);
  out->lens_height_m = st.t_w[2];
  out->tilt_estimated = tilt_estimated;
  out->motion_estimated = active_[kVx];
  out->motion_held = !active_[kVx] && motion_.valid;
  out->cam_vx_mps = st.vx;
  out->cam_vy_mps = st.vy;
  out->yaw_rate_radps = st.w;
  return true;
}

}  // namespace ceilpose
