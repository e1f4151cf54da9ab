#include "pipeline/lsq_solver.h"

#include <algorithm>
#include <cmath>

#include "core/length_2d.h"
#include "core/small_matrix.h"

namespace ceilpose {
namespace {

// The free-tilt fit is skipped when one linearised step from the held fit
// promises less than this share of lsq_tilt_select_chi2: a wide margin for
// the step's linearisation (it matched the fit within a few percent).
constexpr double kTiltScoreShare = 0.25;

}  // namespace

LsqSolver::LsqSolver() {
  for (std::vector<PointTerms>& slot : terms_) slot.resize(points_.size());
}

const char* to_string(TiltChoice choice) {
  switch (choice) {
    case TiltChoice::kNotAllowed:
      return "not_allowed";
    case TiltChoice::kHeldFits:
      return "held_fits";
    case TiltChoice::kFreeFailed:
      return "free_failed";
    case TiltChoice::kFreeFits:
      return "free_fits";
  }
  return "unknown";
}

bool LsqSolver::solve(const ViewGeometry& view, const PositioningParams& params,
                      std::span<const MarkerObservation> markers, std::span<const MarkerFix> fixes,
                      std::span<bool> use, const CameraMotion& motion, LsqResult* out) {
  // 1. The points and the seed.
  Fit seed;
  // A global shutter has no motion within the frame to hold or estimate.
  seed.model.motion = view.intrinsics().readout_ms > 0.0 ? motion : CameraMotion{};
  std::copy(use.begin(), use.end(), seed.use.begin());
  seed.markers = gather_points(view, params, markers, fixes, use, seed.model, &seed.state);
  if (seed.markers == 0 || point_count_ < params.lsq_min_points) return false;
  const bool motion_free = motion_observable(view, params, use, seed.markers);
  seed.model.active = {
      true,        true,        true,        false,           false, params.lsq_estimate_height,
      motion_free, motion_free, motion_free, edge_points_ > 0};

  // 2. Which tilt model the points support, each fit with its own marker
  // rejection.
  int iterations = 0;
  const Fit fit = choose_tilt_model(view, params, fixes, seed, &iterations, out);
  if (!std::isfinite(fit.cost)) return false;
  const std::span<const bool> kept(fit.use.data(), use.size());

  // 3. Accept only a solution that explains the points.
  const int n = fit.residuals;
  if (n < 2 * params.lsq_min_points) return false;  // two residuals a point
  const double rms = rms_px(view, kept, fit.state, n);
  if (!(rms <= params.lsq_max_rms_px)) return false;

  // 4. The covariance.
  out->robot =
      view.robot_from_camera(fit.state.t_w[0], fit.state.t_w[1], camera_yaw_of(fit.state.r_wc));
  if (!covariance_.robot_covariance(view, params, fit.model, points(), terms(fit.terms_slot), fixes,
                                    use, kept, fit.state, fit.a, fit.wr2, n, out->robot,
                                    &out->covariance))
    return false;
  out->rms_px = rms;
  out->markers = fit.markers;
  out->rejected = seed.markers - fit.markers;
  out->points = 0;
  for (const LsqPoint& pt : points()) out->points += kept[pt.fix] ? 1 : 0;
  out->iterations = iterations;
  camera_tilt_of(fit.state.r_wc, &out->tilt_x_rad, &out->tilt_y_rad);
  out->lens_height_m = fit.state.t_w[2];
  out->tilt_estimated = fit.model.tilt_free();
  out->motion_estimated = fit.model.motion_free();
  out->motion_held = !fit.model.motion_free() && fit.model.motion.valid;
  out->cam_vx_mps = fit.state.vx;
  out->cam_vy_mps = fit.state.vy;
  out->yaw_rate_radps = fit.state.w;
  out->edge_offset_px = fit.state.edge_offset_px;
  std::copy(kept.begin(), kept.end(), use.begin());
  return true;
}

// 1. Correspondences of the markers in use (a marker without measured points
// still gives its centre and its two rectangle centres), and the seed: the
// Change of Axes answers averaged, nominal tilt and height, the motion held.
// Returns the markers used.
int LsqSolver::gather_points(const ViewGeometry& view, const PositioningParams& params,
                             std::span<const MarkerObservation> markers,
                             std::span<const MarkerFix> fixes, std::span<const bool> use,
                             const LsqModel& model, LsqState* seed) {
  const CeilingLayout& layout = view.layout();
  const CameraIntrinsics& k = view.intrinsics();
  point_count_ = 0;
  edge_points_ = 0;
  int marker_count = 0;
  double sin_sum = 0.0, cos_sum = 0.0, x_sum = 0.0, y_sum = 0.0;
  for (int f = 0; f < static_cast<int>(fixes.size()); ++f) {
    if (!use[f]) continue;
    const MarkerFix& fix = fixes[f];
    const MarkerObservation& m = markers[fix.index];
    const MarkerPlacement::Rotation rotation = fix.placement->rotation();
    auto add = [&](double e_m, double n_m, double u_px, double v_px, double normal_u = 0.0,
                   double normal_v = 0.0) {
      if (point_count_ >= static_cast<int>(points_.size())) return;
      if (!std::isfinite(u_px) || !std::isfinite(v_px) || !std::isfinite(e_m) ||
          !std::isfinite(n_m) || !std::isfinite(normal_u) || !std::isfinite(normal_v)) {
        return;
      }
      LsqPoint& p = points_[point_count_++];
      undistort_pixel(k, u_px, v_px, &p.x_n, &p.y_n);
      p.normal_x = p.normal_y = 0.0;
      if (normal_u != 0.0 || normal_v != 0.0) {
        // The normal as the residual sees it: undistorted, in f-scaled
        // normalized coordinates, a pixel's step along it.
        double x1 = 0.0, y1 = 0.0;
        undistort_pixel(k, u_px + normal_u, v_px + normal_v, &x1, &y1);
        const double nx = k.fx * (x1 - p.x_n), ny = k.fy * (y1 - p.y_n);
        const double len = length_2d(nx, ny);
        if (!(len > 0.0)) {
          --point_count_;
          return;
        }
        p.normal_x = nx / len;
        p.normal_y = ny / len;
        ++edge_points_;
      }
      p.tau_s = row_time_s(k, v_px);
      double x_m = 0.0, y_m = 0.0;
      fix.placement->world_point(rotation, e_m, n_m, &x_m, &y_m);
      p.world = {x_m, y_m, layout.height_m};
      p.fix = f;
    };
    if (m.point_count > 0) {
      for (int i = 0; i < std::min(m.point_count, kMaxPointsPerMarker); ++i) {
        const MarkerPointObservation& o = m.points[i];
        if (o.is_edge() && !params.lsq_edge_points) continue;
        add(o.e_m, o.n_m, o.u_px, o.v_px, o.normal_u, o.normal_v);
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
    *seed = held_motion(model, *seed);
  }
  return marker_count;
}

// 2. The tilt decision. Held tilt is fitted from the seed (and again once
// the edge points are weighed against the centroids), free tilt from the
// held fit's pose, each with its own marker rejection. Tilt trades off against translation
// so closely that estimating it costs ~10x the position noise of holding it,
// and on a ceiling whose markers are a little off their places a free tilt
// "explains" the offsets by rejecting a good marker and moving the pose by
// decimetres. So the free model is chosen only when it keeps as many
// markers, finds a tilt a real mount can have (lsq_max_tilt_rad), and
// explains the points significantly better (lsq_tilt_select_chi2 times its
// own noise).
LsqSolver::Fit LsqSolver::choose_tilt_model(const ViewGeometry& view,
                                            const PositioningParams& params,
                                            std::span<const MarkerFix> fixes, const Fit& seed,
                                            int* iterations, LsqResult* out) {
  // Each fit's trials trade slots with trial_slot_ alone: slot 1 stays the
  // free fit's while the held fit is optimised.
  Fit held = seed;
  held.terms_slot = 0;
  trial_slot_ = 2;
  held.want_tilt_columns = params.lsq_estimate_tilt && seed.markers >= params.lsq_tilt_min_markers;
  optimise(view, params, fixes, &held, iterations);
  if (reweigh_edges(view, &held)) optimise(view, params, fixes, &held, iterations);
  if (!params.lsq_estimate_tilt || seed.markers < params.lsq_tilt_min_markers) {
    out->tilt_choice = TiltChoice::kNotAllowed;
    return held;
  }
  // Most frames: the free fit could not explain the points much better, and
  // one linearised step from the held fit shows it without the fit.
  if (std::isfinite(held.cost) && held.markers == seed.markers) {
    const double predicted_chi2 = free_tilt_gain_chi2(view, params, held);
    if (predicted_chi2 < kTiltScoreShare * params.lsq_tilt_select_chi2) {
      out->tilt_choice = TiltChoice::kHeldFits;
      out->tilt_chi2 = predicted_chi2;
      return held;
    }
  }
  // From the held fit's pose, which is nearer the free optimum than the
  // seed is (fewer iterations), with the seed's markers: the free model
  // makes its own rejections.
  Fit free = seed;
  free.terms_slot = 1;
  if (std::isfinite(held.cost)) free.state = held.state;
  free.state.edge_weight = held.state.edge_weight;
  free.model.active[kLsqTiltX] = free.model.active[kLsqTiltY] = true;
  optimise(view, params, fixes, &free, iterations);

  double ta = 0.0, tb = 0.0;
  camera_tilt_of(free.state.r_wc, &ta, &tb);
  const bool plausible = std::isfinite(free.cost) && free.model.tilt_free() &&
                         free.markers >= held.markers &&
                         std::hypot(ta - view.mount().tilt_x_rad, tb - view.mount().tilt_y_rad) <=
                             params.lsq_max_tilt_rad;
  if (!plausible) {
    out->tilt_choice = TiltChoice::kFreeFailed;
    return held;
  }
  if (!std::isfinite(held.cost)) {
    out->tilt_choice = TiltChoice::kFreeFits;
    return free;
  }
  // The evidence: how much better the free model explains the points, in
  // units of its own noise; and, only when that is significant, what leaving
  // the tilt out would cost: how far the free pose is from the held one, in
  // units of the free pose's own standard deviation (from the free fit's
  // normal matrix: level views, the common case, skip it).
  const double sigma2 = free.cost / std::max(1, free.residuals - free.model.free_count());
  out->tilt_chi2 = sigma2 > 0.0 ? (held.cost - free.cost) / sigma2 : 0.0;
  out->tilt_shift_m =
      std::hypot(free.state.t_w[0] - held.state.t_w[0], free.state.t_w[1] - held.state.t_w[1]);
  const bool better = out->tilt_chi2 > params.lsq_tilt_select_chi2;
  bool matters = false;
  if (better) {
    out->tilt_free_sigma_m = position_sigma_m(free.model, free.a, free.wr2, free.residuals);
    matters = out->tilt_shift_m > params.lsq_tilt_select_shift_sigmas * out->tilt_free_sigma_m;
  }
  out->tilt_choice = better && matters ? TiltChoice::kFreeFits : TiltChoice::kHeldFits;
  return better && matters ? free : held;
}

// How much better, in units of its own noise (chi-square), a free tilt
// would explain the held fit's points after one Gauss-Newton step
// from it: b^T A^-1 b of the normal equations with the tilt freed, at the
// held optimum (where the held unknowns' part of b is ~0). For a problem as
// near linear as this one it is what the free fit finds to a few percent,
// without the 3-4 passes over the points of the free fit, and without one of
// its own: the held fit's last pass gathered the tilt's rows
// (Fit::tilt_columns); only the tilt's prior is added.
double LsqSolver::free_tilt_gain_chi2(const ViewGeometry& view, const PositioningParams& params,
                                      const Fit& held) const {
  LsqModel model = held.model;
  model.active[kLsqTiltX] = model.active[kLsqTiltY] = true;
  LsqNormal a = held.a;
  LsqVector b = held.b, step{};
  double cost = 0.0;
  if (held.tilt_columns) {
    cost = add_tilt_prior(view, params, held.state, 0.0, &a, &b);
  } else {
    // The held fit took no trial step: one pass of its own.
    const std::span<const bool> use(held.use.data(), held.use.size());
    double wr2 = 0.0;
    int n = 0;
    cost = accumulate(view, params, points(), use, held.state, model, true, &a, &b, &wr2, &n) +
           prior_cost(view, params, model, held.state, &a, &b);
  }
  if (!std::isfinite(cost) || !solve_spd<kLsqParams>(a, model.active, b, &step)) return INFINITY;
  double gain = 0.0;
  for (int i = 0; i < kLsqParams; ++i) gain += b[i] * step[i];
  // In units of the free fit's noise, as choose_tilt_model weighs it: what
  // the held cost leaves after the step, per degree of freedom.
  const double sigma2 = (held.cost - gain) / std::max(1, held.residuals - model.free_count());
  return sigma2 > 0.0 ? gain / sigma2 : INFINITY;
}

// The 1-sigma of the optical centre's horizontal position, metres, from the
// normal equations `a` of a fit whose Huber-weighted squared residuals are
// wr2 over n residuals; infinite when `a` is singular.
double LsqSolver::position_sigma_m(const LsqModel& model, const LsqNormal& a, double wr2,
                                   int n) const {
  const double sigma2 = wr2 / std::max(1, n - model.free_count());
  double var_m2 = 0.0;
  for (int axis : {kLsqTx, kLsqTy}) {
    LsqVector e{}, g{};
    e[axis] = 1.0;
    if (!solve_spd<kLsqParams>(a, model.active, e, &g)) return INFINITY;
    var_m2 += sigma2 * g[axis];
  }
  return std::sqrt(var_m2);
}

// Levenberg–Marquardt with Huber weights (IRLS) over the model's free
// unknowns; then drops the worst marker if its RMS residual exceeds
// lsq_marker_reject_px and solves again from where it is, at most
// lsq_max_rejections times. Leaves fit->cost infinite when the solve
// diverged.
void LsqSolver::optimise(const ViewGeometry& view, const PositioningParams& params,
                         std::span<const MarkerFix> fixes, Fit* fit, int* iterations) {
  constexpr int kN = kLsqParams;
  constexpr double kLambdaStart = 1e-4;
  // A step's predicted gain, as a share of the cost, below which the fit
  // has converged: with n residuals it moves the pose by about
  // √(n · 1e-6) of the pose's own standard deviation (0.01 for 100). At
  // 1e-9 most fits took a second step of that size, a pass over the points
  // each (7 % of a tracked frame's instructions); the poses moved by
  // 0.1-0.7 µm on the drive, stress and tilt sets, 54 µm where a hand-laid
  // ceiling without its map leaves millimetres of residual.
  constexpr double kNegligibleGain = 1e-6;
  LsqState& st = fit->state;
  const std::span<bool> use(fit->use.data(), fixes.size());
  LsqNormal a{};
  LsqVector b{};
  double wr2 = 0.0;
  int n = 0;
  for (int pass = 0; pass <= params.lsq_max_rejections; ++pass) {
    fit->cost = INFINITY;
    double lambda = kLambdaStart;
    // The columns a trial's pass fills: the model's, and the tilt's when
    // asked.
    LsqModel columns = fit->model;
    if (fit->want_tilt_columns) columns.active[kLsqTiltX] = columns.active[kLsqTiltY] = true;
    bool tilt_columns = false;
    double cost = accumulate(view, params, points(), use, st, fit->model, true, &a, &b, &wr2, &n,
                             terms(fit->terms_slot)) +
                  prior_cost(view, params, fit->model, st, &a, &b);
    if (!std::isfinite(cost)) return;
    for (int it = 0; it < params.lsq_max_iterations; ++it, ++*iterations) {
      LsqNormal damped = a;
      for (int i = 0; i < kN; ++i) damped[i * kN + i] *= 1.0 + lambda;
      LsqVector step{};
      if (!solve_spd<kN>(damped, fit->model.active, b, &step)) return;
      // Converged when a Gauss–Newton step (damping at most its start)
      // would lower the cost by a negligible share: the trial's rounding
      // would then decide whether it is "better", and every refused trial
      // costs a pass over the points (seen: five in a row, each predicted
      // to gain 1e-19 px², for an edge offset's 1e-7 px step).
      double gain = 0.0;
      for (int i = 0; i < kN; ++i) gain += b[i] * step[i];
      if (lambda <= kLambdaStart && gain <= kNegligibleGain * cost) break;
      const LsqState trial = stepped(st, step);
      LsqNormal ta{};
      LsqVector tb{};
      double twr2 = 0.0;
      int tn = 0;
      const double trial_cost =
          accumulate(view, params, points(), use, trial, columns, true, &ta, &tb, &twr2, &tn,
                     fit->terms_slot < 0 ? std::span<PointTerms>{} : terms(trial_slot_)) +
          prior_cost(view, params, fit->model, trial, &ta, &tb);
      if (trial_cost <= cost) {
        st = trial;
        if (fit->terms_slot >= 0) std::swap(fit->terms_slot, trial_slot_);
        cost = trial_cost;
        a = ta;
        b = tb;
        wr2 = twr2;
        n = tn;
        tilt_columns = fit->want_tilt_columns;
        lambda = std::max(lambda * 0.1, 1e-9);
        double step_norm = 0.0;
        for (double v : step) step_norm = std::max(step_norm, std::abs(v));
        if (step_norm < params.lsq_step_tolerance) break;
      } else {
        lambda *= 10.0;
        if (lambda > 1e6) break;
      }
    }
    fit->cost = cost;
    fit->a = a;
    fit->b = b;
    fit->tilt_columns = tilt_columns;
    fit->wr2 = wr2;
    fit->residuals = n;
    if (fit->markers <= 1 || pass == params.lsq_max_rejections) break;
    const int worst = worst_marker(view, params, fixes, *fit);
    if (worst < 0) break;
    use[worst] = false;
    --fit->markers;
    LsqModel& model = fit->model;
    if (fit->markers < params.lsq_tilt_min_markers)
      model.active[kLsqTiltX] = model.active[kLsqTiltY] = false;
    if (model.motion_free() && !motion_observable(view, params, use, fit->markers)) {
      model.active[kLsqVx] = model.active[kLsqVy] = model.active[kLsqYawRate] = false;
      st = held_motion(model, st);
    }
    if (model.active[kLsqEdgeOffset] && !edge_points_in_use(use)) {
      model.active[kLsqEdgeOffset] = false;
      st.edge_offset_px = 0.0;
    }
  }
}

// The marker with the largest RMS residual above lsq_marker_reject_px, or -1.
int LsqSolver::worst_marker(const ViewGeometry& view, const PositioningParams& params,
                            std::span<const MarkerFix> fixes, const Fit& fit) const {
  int worst = -1;
  double worst_rms2 = params.lsq_marker_reject_px * params.lsq_marker_reject_px;
  for (int f = 0; f < static_cast<int>(fixes.size()); ++f) {
    if (!fit.use[f]) continue;
    double sum = 0.0;
    int residuals = 0;
    for (const LsqPoint& pt : points()) {
      if (pt.fix != f) continue;
      sum += residual2_px(view, fit.state, pt);
      residuals += pt.residuals();
    }
    // Per point: two residuals (an edge point has one).
    if (residuals > 0 && 2.0 * sum / residuals > worst_rms2) {
      worst_rms2 = 2.0 * sum / residuals;
      worst = f;
    }
  }
  return worst;
}

// Whether the points span enough rows (lsq_motion_min_row_span of the
// readout) and markers (lsq_motion_min_markers) to estimate the motion.
bool LsqSolver::motion_observable(const ViewGeometry& view, const PositioningParams& params,
                                  std::span<const bool> use, int marker_count) const {
  const double readout_s = view.intrinsics().readout_ms * 1e-3;
  if (!(readout_s > 0.0) || marker_count < params.lsq_motion_min_markers) return false;
  double lo = INFINITY, hi = -INFINITY;
  for (const LsqPoint& pt : points()) {
    if (!use[pt.fix]) continue;
    lo = std::min(lo, pt.tau_s);
    hi = std::max(hi, pt.tau_s);
  }
  return hi - lo >= params.lsq_motion_min_row_span * readout_s;
}

// Edge points and centroids weighed by their own scatter in this frame: a
// centroid averages hundreds of pixels, an edge point a dozen samples, so
// noise, JPEG and blur move the second more. From the held fit's residuals
// (per residual, each kind); true when the weight changed. Never above 1:
// where edges scatter less, the centroids' systematic errors do not show in
// their scatter. Stress set (noise sigma 6, JPEG 60, blur) 0.20 / 0.61 ->
// 0.15 / 0.45 mm; tilted and level independent renders unchanged.
bool LsqSolver::reweigh_edges(const ViewGeometry& view, Fit* fit) const {
  if (!std::isfinite(fit->cost) || !fit->model.active[kLsqEdgeOffset]) return false;
  LsqState st = fit->state;
  st.edge_weight = 1.0;
  double centroid_r2 = 0.0, edge_r2 = 0.0;
  int centroid_n = 0, edge_n = 0;
  for (const LsqPoint& pt : points()) {
    if (!fit->use[pt.fix]) continue;
    const double r2 = residual2_px(view, st, pt);
    if (pt.is_edge()) {
      edge_r2 += r2;
      ++edge_n;
    } else {
      centroid_r2 += r2;
      centroid_n += 2;
    }
  }
  if (edge_n < 3 || centroid_n < 3 || !(edge_r2 > 0.0) || !(centroid_r2 > 0.0)) return false;
  const double w = std::min(1.0, std::sqrt((centroid_r2 / centroid_n) / (edge_r2 / edge_n)));
  fit->state.edge_weight = w;
  return w < 1.0;
}

// Whether any marker in use has an edge point (else the edge offset has no
// column in the normal equations).
bool LsqSolver::edge_points_in_use(std::span<const bool> use) const {
  for (const LsqPoint& pt : points())
    if (use[pt.fix] && pt.is_edge()) return true;
  return false;
}

// 3. RMS reprojection residual of the points in use, pixels, per point (two
// residuals; n residuals in all).
double LsqSolver::rms_px(const ViewGeometry& view, std::span<const bool> use, const LsqState& st,
                         int n) const {
  double sum_r2 = 0.0;
  for (const LsqPoint& pt : points()) {
    if (!use[pt.fix]) continue;
    sum_r2 += residual2_px(view, st, pt);
  }
  return std::sqrt(2.0 * sum_r2 / n);
}

}  // namespace ceilpose
