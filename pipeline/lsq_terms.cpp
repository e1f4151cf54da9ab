#include "pipeline/lsq_terms.h"

#include <algorithm>
#include <cmath>

#include "core/small_angle.h"
#include "core/small_matrix.h"

namespace ceilpose {
namespace {

constexpr int kN = kLsqParams;

// Rotation by an angle of sine s and cosine c about the world's vertical,
// applied on the left: only the first two rows mix, and the third stays
// (a full 3×3 product, 15 of whose 27 multiplications are by 0 or 1, cost
// a rolling-shutter tracked frame 2 % more instructions).
Mat3 turned(const Mat3& r, double s, double c) {
  Mat3 out = r;
  for (int j = 0; j < 3; ++j) {
    out[j] = c * r[j] - s * r[3 + j];
    out[3 + j] = s * r[j] + c * r[3 + j];
  }
  return out;
}

// The optical centre when a point tau_s after the centre row was exposed:
// t moved along its arc (v, w).
Vec3 centre_at(const LsqState& st, double tau_s) {
  double dx_m = 0.0, dy_m = 0.0;
  arc_displacement(st.vx, st.vy, st.w, tau_s, &dx_m, &dy_m);
  return {st.t_w[0] + dx_m, st.t_w[1] + dy_m, st.t_w[2]};
}

// The camera then: centre_at's, and Exp(w·tau·z)·R, whose turn has sine
// sin_wt and cosine cos_wt.
void camera_at(const LsqState& st, double tau_s, double sin_wt, double cos_wt, Vec3* t_w,
               Mat3* r_wc) {
  *t_w = centre_at(st, tau_s);
  *r_wc = turned(st.r_wc, sin_wt, cos_wt);
}

void camera_at(const LsqState& st, double tau_s, Vec3* t_w, Mat3* r_wc) {
  if (tau_s == 0.0) {  // global shutter: no arithmetic, the same bits
    *t_w = st.t_w;
    *r_wc = st.r_wc;
    return;
  }
  double sin_wt = 0.0, cos_wt = 1.0;
  small_angle_sincos(st.w * tau_s, &sin_wt, &cos_wt);
  camera_at(st, tau_s, sin_wt, cos_wt, t_w, r_wc);
}

// An edge point keeps only its residual's component across the edge, less
// the edge offset (observed = projected + offset·normal).
void across_edge(const LsqPoint& pt, double offset_px, double weight, double* x, double* y) {
  if (!pt.is_edge()) return;
  *x = weight * (pt.normal_x * *x + pt.normal_y * *y - offset_px);
  *y = 0.0;
}

}  // namespace

int LsqModel::free_unknowns(std::array<int, kLsqParams>* out) const {
  int n = 0;
  for (int c = 0; c < kLsqParams; ++c)
    if (active[c]) (*out)[static_cast<size_t>(n++)] = c;
  return n;
}

int LsqModel::free_count() const {
  int n = 0;
  for (bool a : active) n += a ? 1 : 0;
  return n;
}

PointCamera centre_camera(const LsqState& st) {
  const Mat3 lev = level_rotation(camera_yaw_of(st.r_wc));
  return {{},
          mat_transpose(st.r_wc),
          {{{0.0, 0.0, 1.0}, {lev[0], lev[3], lev[6]}, {lev[1], lev[4], lev[7]}}},
          st.edge_offset_px,
          st.edge_weight,
          st.vx,
          st.vy,
          st.w};
}

PointCamera point_camera(const LsqState& st, const LsqPoint& pt, const PointCamera& centre,
                         bool with_axes) {
  PointCamera cam = centre;
  Vec3 t_w = st.t_w;
  if (pt.tau_s != 0.0) {
    // One sine and cosine for the camera's turn and its axes'.
    double sa = 0.0, ca = 1.0;
    small_angle_sincos(st.w * pt.tau_s, &sa, &ca);
    t_w = centre_at(st, pt.tau_s);
    // turned() mixes R's first two rows, which are Rᵀ's first two columns:
    // the same products, on the centre row's Rᵀ in place.
    for (int i = 0; i < 3; ++i) {
      const double c0 = centre.rt[3 * i], c1 = centre.rt[3 * i + 1];
      cam.rt[3 * i] = ca * c0 - sa * c1;
      cam.rt[3 * i + 1] = sa * c0 + ca * c1;
    }
    if (with_axes) {
      // The turn about the vertical turns the level axes with it; the yaw
      // axis stays vertical.
      for (int k = 1; k < 3; ++k) {
        const Vec3 l = centre.axis[k];
        cam.axis[k] = {ca * l[0] - sa * l[1], sa * l[0] + ca * l[1], l[2]};
      }
    }
  }
  cam.d = {pt.world[0] - t_w[0], pt.world[1] - t_w[1], pt.world[2] - t_w[2]};
  return cam;
}

bool point_residual(const ViewGeometry& view, const LsqPoint& pt, const PointCamera& cam,
                    double* rx, double* ry) {
  const Vec3 p = mat_vec(cam.rt, cam.d);
  if (p[2] < 1e-3) return false;
  *rx = normalized_residual_px(view.intrinsics().fx, pt.x_n, p[0], p[2]);
  *ry = normalized_residual_px(view.intrinsics().fy, pt.y_n, p[1], p[2]);
  across_edge(pt, cam.edge_offset_px, cam.edge_weight, rx, ry);
  return true;
}

// For a ceiling point P, d = P − t and p = Rᵀd: ∂p/∂t = −Rᵀ, ∂p/∂ω = Rᵀ[d]×,
// and x = X/Z, y = Y/Z give ∂x/∂p = (1/Z, 0, −X/Z²), ∂y/∂p = (0, 1/Z, −Y/Z²).
// A point exposed tau after the centre row has its camera at
// t + v·tau + w·tau²/2·(−vy, vx) (arc_displacement) and Exp(w·tau·z)·R, so
// v and w move it as t and the yaw do, tau times as much, and each also
// turns the other's share of the arc.
void point_jacobian(const ViewGeometry& view, const LsqPoint& pt, const PointCamera& cam,
                    double* jx, double* jy, bool with_tilt, bool with_motion) {
  const double fx = view.intrinsics().fx, fy = view.intrinsics().fy;
  const Vec3& d = cam.d;
  const Vec3 p = mat_vec(cam.rt, d);
  const double iz = 1.0 / p[2];
  // ∂r/∂param = −f·∂(projection)/∂param, from the column ∂p/∂param.
  auto column = [&](int c, const Vec3& dp) {
    jx[c] = -fx * iz * (dp[0] - p[0] * iz * dp[2]);
    jy[c] = -fy * iz * (dp[1] - p[1] * iz * dp[2]);
  };
  for (int c : {kLsqTx, kLsqTy, kLsqTz}) {
    const int axis = c == kLsqTz ? 2 : c;
    column(c, {-cam.rt[axis], -cam.rt[3 + axis], -cam.rt[6 + axis]});
  }
  const int rot_cols[3] = {kLsqYaw, kLsqTiltX, kLsqTiltY};
  for (int k = 0; k < 3; ++k) {
    if (k > 0 && !with_tilt) {
      jx[rot_cols[k]] = jy[rot_cols[k]] = 0.0;
      continue;
    }
    const Vec3& w3 = cam.axis[k];
    const Vec3 cross{d[1] * w3[2] - d[2] * w3[1], d[2] * w3[0] - d[0] * w3[2],
                     d[0] * w3[1] - d[1] * w3[0]};  // [d]×·w = d × w
    column(rot_cols[k], mat_vec(cam.rt, cross));
  }
  const double t = pt.tau_s, half_t2 = 0.5 * t * t, turn = cam.w_radps * half_t2;
  for (double* j : {jx, jy}) {
    if (!with_motion) {
      j[kLsqVx] = j[kLsqVy] = j[kLsqYawRate] = 0.0;
      continue;
    }
    j[kLsqVx] = t * j[kLsqTx] + turn * j[kLsqTy];
    j[kLsqVy] = t * j[kLsqTy] - turn * j[kLsqTx];
    j[kLsqYawRate] = t * j[kLsqYaw] + half_t2 * (cam.vx_mps * j[kLsqTy] - cam.vy_mps * j[kLsqTx]);
  }
  jx[kLsqEdgeOffset] = jy[kLsqEdgeOffset] = 0.0;
  if (!pt.is_edge()) return;
  // Across the edge: the columns left zero stay zero.
  for (int c = 0; c < kN; ++c) {
    const bool zero = (!with_tilt && (c == kLsqTiltX || c == kLsqTiltY)) ||
                      (!with_motion && (c == kLsqVx || c == kLsqVy || c == kLsqYawRate));
    if (!zero) across_edge(pt, 0.0, cam.edge_weight, &jx[c], &jy[c]);
  }
  jx[kLsqEdgeOffset] = -cam.edge_weight;
}

double residual2_px(const ViewGeometry& view, const LsqState& st, const LsqPoint& pt) {
  Vec3 t_w;
  Mat3 r_wc;
  camera_at(st, pt.tau_s, &t_w, &r_wc);
  const Vec3 p = mat_vec(mat_transpose(r_wc),
                         {pt.world[0] - t_w[0], pt.world[1] - t_w[1], pt.world[2] - t_w[2]});
  double rx = normalized_residual_px(view.intrinsics().fx, pt.x_n, p[0], p[2]);
  double ry = normalized_residual_px(view.intrinsics().fy, pt.y_n, p[1], p[2]);
  across_edge(pt, st.edge_offset_px, st.edge_weight, &rx, &ry);
  return rx * rx + ry * ry;
}

double accumulate(const ViewGeometry& view, const PositioningParams& params,
                  std::span<const LsqPoint> points, std::span<const bool> use, const LsqState& st,
                  const LsqModel& model, bool with_jacobian, LsqNormal* a, LsqVector* b,
                  double* sum_w_r2, int* residuals, std::span<PointTerms> terms) {
  const double k = params.lsq_huber_px;
  const bool keep = with_jacobian && !terms.empty();
  const PointCamera centre = centre_camera(st);
  // Only the free unknowns' rows and columns: a fit frees 4-6 of the 10, and
  // the update is most of a point's cost.
  std::array<int, kN> free{};
  const int free_n = model.free_unknowns(&free);
  if (with_jacobian) {
    a->fill(0.0);
    b->fill(0.0);
  }
  double cost = 0.0, wr2 = 0.0;
  int n = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const LsqPoint& pt = points[i];
    if (keep) terms[i].kept = use[pt.fix];
    if (!use[pt.fix]) continue;
    const PointCamera cam = point_camera(st, pt, centre, with_jacobian);
    double rx = 0.0, ry = 0.0;
    if (!point_residual(view, pt, cam, &rx, &ry)) return INFINITY;
    const double r = std::sqrt(rx * rx + ry * ry);
    const double w = r <= k ? 1.0 : k / r;
    cost += r <= k ? r * r : 2.0 * k * r - k * k;
    wr2 += w * r * r;
    n += pt.residuals();
    if (!with_jacobian) continue;
    double own_jx[kN], own_jy[kN];
    double* jx = keep ? terms[i].jx : own_jx;
    double* jy = keep ? terms[i].jy : own_jy;
    if (keep) terms[i].rx = rx, terms[i].ry = ry;
    point_jacobian(view, pt, cam, jx, jy, model.tilt_free(), model.motion_free());
    if (pt.is_edge()) {
      // One residual, across the edge (ry and jy are zero): half the terms.
      for (int i = 0; i < free_n; ++i) {
        const int r1 = free[i];
        (*b)[r1] -= w * (jx[r1] * rx);
        for (int j = i; j < free_n; ++j) {
          const int c = free[j];
          (*a)[r1 * kN + c] += w * (jx[r1] * jx[c]);
        }
      }
      continue;
    }
    for (int i = 0; i < free_n; ++i) {
      const int r1 = free[i];
      (*b)[r1] -= w * (jx[r1] * rx + jy[r1] * ry);
      for (int j = i; j < free_n; ++j) {
        const int c = free[j];
        (*a)[r1 * kN + c] += w * (jx[r1] * jx[c] + jy[r1] * jy[c]);
      }
    }
  }
  if (with_jacobian) {
    for (int i = 0; i < free_n; ++i)
      for (int j = 0; j < i; ++j) (*a)[free[i] * kN + free[j]] = (*a)[free[j] * kN + free[i]];
  }
  *sum_w_r2 = wr2;
  *residuals = n;
  return cost;
}

// The motion's prior is the caller's motion, or rest with
// lsq_motion_prior_mps / _radps per pixel of residual; the caller's sigmas are
// floored. The tilt's soft prior keeps it near the mount's nominal tilt when
// the points cannot separate it from translation; its weight is that of one
// 1-pixel residual per lsq_tilt_prior_rad.
double prior_cost(const ViewGeometry& view, const PositioningParams& params, const LsqModel& model,
                  const LsqState& st, LsqNormal* a, LsqVector* b) {
  double motion = 0.0;
  const CameraMotion& told = model.motion;
  if (model.motion_free()) {
    const double wv =
        1.0 / (told.valid ? std::max(told.sigma_v_mps, params.lsq_motion_prior_floor_mps)
                          : params.lsq_motion_prior_mps);
    const double ww =
        1.0 / (told.valid ? std::max(told.sigma_yaw_rate_radps, params.lsq_motion_prior_floor_radps)
                          : params.lsq_motion_prior_radps);
    const LsqState held = held_motion(model, st);
    const double r[3] = {wv * (st.vx - held.vx), wv * (st.vy - held.vy), ww * (st.w - held.w)};
    const double wt[3] = {wv, wv, ww};
    for (int k = 0; k < 3; ++k) {
      motion += r[k] * r[k];
      if (a == nullptr) continue;
      (*a)[(kLsqVx + k) * kN + kLsqVx + k] += wt[k] * wt[k];
      (*b)[kLsqVx + k] -= wt[k] * r[k];
    }
  }
  if (!model.tilt_free()) return motion;
  return add_tilt_prior(view, params, st, motion, a, b);
}

double add_tilt_prior(const ViewGeometry& view, const PositioningParams& params, const LsqState& st,
                      double cost, LsqNormal* a, LsqVector* b) {
  double ta = 0.0, tb = 0.0;
  camera_tilt_of(st.r_wc, &ta, &tb);
  const double w = 1.0 / params.lsq_tilt_prior_rad;
  const double ra = w * (ta - view.mount().tilt_x_rad), rb = w * (tb - view.mount().tilt_y_rad);
  if (a != nullptr) {
    (*a)[kLsqTiltX * kN + kLsqTiltX] += w * w;
    (*a)[kLsqTiltY * kN + kLsqTiltY] += w * w;
    (*b)[kLsqTiltX] -= w * ra;
    (*b)[kLsqTiltY] -= w * rb;
  }
  return cost + ra * ra + rb * rb;
}

LsqState held_motion(const LsqModel& model, const LsqState& st) {
  LsqState out = st;
  const CameraMotion& m = model.motion;
  out.vx = m.valid ? m.vx_mps : 0.0;
  out.vy = m.valid ? m.vy_mps : 0.0;
  out.w = m.valid ? m.yaw_rate_radps : 0.0;
  return out;
}

LsqState stepped(const LsqState& st, const LsqVector& step) {
  LsqState out = st;
  out.t_w[0] += step[kLsqTx];
  out.t_w[1] += step[kLsqTy];
  out.t_w[2] += step[kLsqTz];
  const Mat3 lev = level_rotation(camera_yaw_of(st.r_wc));
  Vec3 w{0.0, 0.0, step[kLsqYaw]};
  for (int r = 0; r < 3; ++r)
    w[r] += step[kLsqTiltX] * lev[r * 3] + step[kLsqTiltY] * lev[r * 3 + 1];
  out.r_wc = mat_mul(exp_so3(w), st.r_wc);
  out.vx += step[kLsqVx];
  out.vy += step[kLsqVy];
  out.w += step[kLsqYawRate];
  out.edge_offset_px += step[kLsqEdgeOffset];
  return out;
}

}  // namespace ceilpose
