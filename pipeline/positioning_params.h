#pragma once
// Parameters of the positioning stages and the temporal filter. The defaults
// here are the single source of truth; config/ceilpose.yaml mirrors them.
// Every field: meaning, unit, effect, when to tune.
#include <cmath>

#include "core/positioning_mode.h"

namespace ceilpose {

struct PositioningParams {
  // The positioning mode (positioning.mode; `locate --mode`): auto picks the
  // best the view allows (lsq, else barycentric, else Change of Axes).
  PositioningMode mode = PositioningMode::kAuto;
  // --- least squares (camera attitude from all marker points) ---
  // Levenberg–Marquardt iterations per solve. Each costs one pass over the
  // points (~1 µs per 100 points). Converges in 3–6 from the thesis-mode
  // seed; raise only if `rms_residual_px` stays high on good views.
  int lsq_max_iterations = 12;
  // Stop when the parameter update is below this (metres / radians).
  double lsq_step_tolerance = 1e-7;
  // Huber threshold on a point's reprojection residual, pixels. Residuals
  // above it get weight k/|r|, so one bad point cannot pull the solution.
  // Set to ~3x the detector's point noise; lower it for cleaner images.
  double lsq_huber_px = 1.5;
  // A marker whose RMS residual after the solve exceeds this (pixels) is
  // dropped and the solve repeated (a marker decoded with a wrong code that
  // happens to be grid-consistent, or a mis-measured one).
  double lsq_marker_reject_px = 4.0;
  // The solution is accepted only if the inliers' RMS residual (pixels) is
  // below this; otherwise auto falls back to the thesis modes.
  double lsq_max_rms_px = 3.0;
  // Fewest point correspondences (over all markers) for lsq. One marker's
  // three points (centre, rectangle centres) already fix position and yaw
  // with tilt held; tilt needs lsq_tilt_min_markers.
  int lsq_min_points = 3;
  // Solve from the rectangles' edge points as well as their centroids
  // (pipeline/rectangle_ends.h). They tell a tilt from a shift marker by
  // marker (tilted independent renders: p99 6.1 -> 2.1 mm; level: median
  // 0.31 -> 0.13 mm), but they also measure each marker's size, so a camera
  // whose focal length or distortion is far off fits them badly: off only
  // while such a camera is being calibrated (survey, calibrate robot).
  bool lsq_edge_points = true;
  // Solve roll/pitch tilt of the camera (true) or hold it at the mount's
  // nominal tilt (false). Tilt costs nothing and absorbs a camera that is not
  // quite level; hold it only for single-marker views (done automatically).
  bool lsq_estimate_tilt = true;
  // The tilt decision (lsq_solver.cpp's choose_tilt_model): the free-tilt
  // fit is chosen only when it lowers the robust cost by more than this many
  // times its residual variance (a likelihood-ratio test on 2 extra
  // parameters)... Above chi²(2)'s 99.99% point (18.4) because real point
  // errors are not Gaussian. Measured on independent renders (tests/pipeline/
  // tilt_decision_test.cpp, 2026-12-03): at 100 every tilt of 0.13–0.19° was
  // left out and cost 5–7 mm; at 20, 1 level frame in 450 chose a tilt
  // (3.1 mm off) and tilted frames of 0.1–3° kept p99 1.9 mm. Raised to 30
  // (2026-12-04) when level 4:2:0 camera frames (NV12, chroma blurred over
  // two rows) of the gradient, noise and clutter sets each had one frame at
  // chi² 20–27 that chose a tilt of 0.03–0.13° (1.1–5.2 mm off); the tilted
  // frames of that test keep their limits. Lower to follow smaller tilts,
  // raise if level views find tilts.
  double lsq_tilt_select_chi2 = 30.0;
  // ... and only when leaving the tilt out would cost position: the free
  // pose must lie more than this many of its own standard deviations from
  // the held one. Below that either answer is as good, and holding the tilt
  // is the more precise.
  double lsq_tilt_select_shift_sigmas = 2.0;
  // Prior standard deviation of the tilt about the nominal mount tilt,
  // radians, weighted as one 1-pixel residual. A guard against divergence on
  // few, clustered points, weak enough not to bias a real tilt.
  double lsq_tilt_prior_rad = 0.2;
  // A free tilt farther than this from the mount's nominal tilt, radians, is
  // not believed: the held model is used. On a hand-laid ceiling (markers
  // 15 mm, 1° off) a few frames "found" tilts of ~15° that moved the pose by
  // half a metre with a residual of 1.7 px; a mount that tilts by more than
  // 5° is a configuration error (mount.tilt_*), not something to follow.
  double lsq_max_tilt_rad = 0.09;
  // Fewest markers for solving tilt; with fewer, tilt is held at nominal
  // (the points of one or two markers cannot separate tilt from position).
  int lsq_tilt_min_markers = 3;
  // Also solve the lens-to-ceiling distance (usually known from config).
  // Only for ceilings of uncertain height; it weakens the position solution.
  bool lsq_estimate_height = false;
  // Marker-level rejection passes after the first solve: each drops the
  // worst marker above lsq_marker_reject_px. More passes survive more wrong
  // markers in one view, at one solve each.
  int lsq_max_rejections = 3;
  // Rolling shutter: the camera's motion during the readout is estimated only
  // from markers spread over at least this share of the readout's rows...
  double lsq_motion_min_row_span = 0.3;
  // ... and at least this many markers; otherwise it is held (at the filter's
  // motion when known, else at rest). Lower both to estimate motion from
  // fewer markers at the cost of a noisier pose.
  int lsq_motion_min_markers = 3;
  // Prior of the motion when the filter gives none: rest, with these
  // standard deviations per pixel of residual, m/s and rad/s. It only
  // conditions a solve whose rows barely tell the motion.
  double lsq_motion_prior_mps = 1.0;
  double lsq_motion_prior_radps = 3.0;
  // Floors on the filter's motion sigmas when they are the prior, m/s and
  // rad/s: a filter that has just missed a turn must not override what the
  // rows say. Raise them if turns in the view come out too smooth.
  double lsq_motion_prior_floor_mps = 0.05;
  double lsq_motion_prior_floor_radps = 0.2;

  // --- grid consistency (rejecting markers whose code disagrees) ---
  // Two markers agree when the camera positions they imply differ by less
  // than this, in grid units. A misread bit moves a marker by ≥ 1 unit, so
  // anything well below 0.5 works; larger tolerates more tilt/distortion.
  double grid_tolerance_units = 0.3;
  // ... and their headings differ by less than this, radians.
  double heading_tolerance_rad = 0.35;
  // A pose is refused when the spacing of the markers in the image puts the
  // ceiling farther or nearer than the configured heights by more than this
  // fraction (median over pairs of consistent markers). With a wrong
  // ceiling or camera height the solvers still fit, under the RMS limit, and
  // poses came out up to 0.74 m off (ceiling 14–17 % farther than
  // configured, docs/cross_check.md). A level camera with the right heights
  // reads within 0.5 %; 3° of tilt moves the median by up to ~3 %. 0
  // disables the check, as does lsq_estimate_height.
  double max_depth_scale_error = 0.08;

  // --- thesis modes ---
  // Markers are considered for the Barycentric triangle only if the triangle
  // of their centres covers at least this area, squared grid units; rejects
  // near-collinear triples whose areal coordinates blow up.
  double barycentric_min_area_units2 = 0.4;
  // Standard deviations reported in the covariance of thesis-mode poses,
  // metres / radians (they have no residuals to derive it from). Set to the
  // measured accuracy of those modes.
  double thesis_sigma_m = 0.01;
  double thesis_sigma_yaw_rad = 0.01;
  // Covariance floor added to lsq's diagonal (metres / radians). The
  // covariance already holds the pixel noise, the map's sigmas and the
  // scatter of the markers about their mapped places (model errors that show
  // in the residuals); it is honest without a floor (mean NEES 2.2-3.8 on
  // perfect, hand-laid and surveyed ceilings; with a 1 mm floor it was 0.01
  // on surveyed ones). Raise for errors the residuals cannot show.
  double lsq_sigma_floor_m = 0.0;
  double lsq_sigma_floor_yaw_rad = 0.0;
};

struct FilterParams {
  bool enabled = true;  // the daemon filters; `locate` only with --filter
  // White-jerk process noise of the constant-acceleration model
  // (core/motion_model.h): square root of the jerk's spectral density,
  // m/s³·√s and rad/s³·√s. Larger follows changes of acceleration faster but
  // smooths less. Tuned on the `drive` set (curves, 0.1-1.5 m/s) and the
  // patrol, whose U-turns start at 2 rad/s at once: at a yaw jerk of 30 the
  // filter gated the turns' first frames and lagged 10 mm; docs/latency.md
  // has the sweep.
  double jerk_sigma_mps3 = 10.0;
  double yaw_jerk_sigma_radps3 = 300.0;
  // Measurement standard deviation floors, metres / radians: a measurement's
  // own covariance is used but never taken as better than this. lsq's
  // covariance is honest now (mean NEES ~3) so the floors are small: at 2 mm
  // the filter trusted its prediction over 0.1 mm measurements and lagged
  // 10 mm on curves.
  double meas_sigma_floor_m = 0.0002;
  double meas_sigma_floor_yaw_rad = 0.0005;
  // Gate on the squared Mahalanobis distance of the innovation (3 DOF).
  // 16.3 is the 99.9% point of chi²(3); raise to accept faster motion. A
  // gated frame publishes no pose: neither the measurement nor the
  // prediction it contradicts.
  double gate_chi2 = 16.3;
  // Innovations smaller than these are never gated (metres / radians), so a
  // very confident filter does not lock out a slightly-off good measurement.
  double gate_min_m = 0.02;
  double gate_min_rad = 0.03;
  // After this many consecutive gated measurements that agree with each
  // other (each within the gate of a filter of their own) the filter
  // believes them (the robot was moved, or the filter diverged) and goes on
  // from their filter. Counted in TemporalFilter::stats().
  int reinit_after_gated = 5;
  // Frames stamped closer together than this (SPEC §4 allows equal stamps)
  // carry no motion the filter can use: fused as one instant, a moving
  // robot's frames were averaged into a pose up to 217 mm behind with an sd
  // of 8 mm; fused 1 ns apart they made a velocity of km/s. Such a frame
  // restarts the filter on its own measurement instead, milliseconds. No
  // camera delivers more than 1000 frames a second.
  double min_frame_interval_ms = 1.0;
  // Without a valid measurement the filter predicts for at most this long,
  // then reports invalid until a measurement re-initialises it, milliseconds.
  double predict_timeout_ms = 500.0;
  // ...and reports its prediction only while a gross error (SPEC §6: 0.25
  // grid units, 5°) lies beyond two standard deviations of it: 1-sigma at
  // most this far, metres, and this much yaw, radians. The yaw jerk noise
  // is sized for sudden turns, so at 30 fps a prediction's yaw sd is ~1.8°
  // one frame on, ~7° two frames on: a long lens that lost its markers for
  // 13 frames published poses up to 117 mm and 42° off (23 of 300 gross)
  // with sds of 311 mm and 520°.
  double coast_max_sd_m = 0.0762;
  double coast_max_yaw_sd_rad = 0.0436;
  // Initial velocity standard deviations, m/s and rad/s.
  double init_velocity_sigma_mps = 0.5;
  double init_yaw_rate_sigma_radps = 1.0;
  // Initial acceleration standard deviations, m/s² and rad/s².
  double init_accel_sigma_mps2 = 1.0;
  double init_yaw_accel_sigma_radps2 = 3.0;
  // How far ahead (or back) of a pose's frame the pose client predicts
  // (ceilpose_client_predict, `pose --at`) before it refuses, milliseconds.
  double predict_horizon_ms = 200.0;
};

// True when a measured depth scale (PoseEstimate::depth_scale, 0 = not
// measured) contradicts the configured heights beyond what `params` allow:
// positioning then refuses the frame. One rule for the positioner and for
// the callers that explain the refusal.
inline bool depth_scale_contradicts_heights(const PositioningParams& params, double depth_scale) {
  return depth_scale > 0.0 && params.max_depth_scale_error > 0.0 && !params.lsq_estimate_height &&
         std::fabs(depth_scale - 1.0) > params.max_depth_scale_error;
}

}  // namespace ceilpose
