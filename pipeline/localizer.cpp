#include "pipeline/localizer.h"

#include <algorithm>
#include <cmath>

#include "core/clock.h"
#include "core/finite.h"
#include "core/small_matrix.h"
#include "pipeline/camera_motion.h"

namespace ceilpose {
namespace {

bool finite_estimate(const PoseEstimate& e) {
  const double pose[] = {e.pose.x_m, e.pose.y_m, e.pose.yaw_rad, e.rms_residual_px,
                         e.time_offset_s};
  return all_finite(pose) && all_finite(e.covariance);
}

bool finite_motion(const MotionEstimate& m) {
  return !m.valid || (all_finite(m.state.x) && all_finite(m.state.p));
}

// Whole sweeps found at half resolution first (detector.halve_whole_sweeps):
// with the filter, where frames are measured at the markers' edges
// (detector.track_edges, in a mode that positions from them), for a camera
// that sees the markers large enough.
bool halved_sweeps(const Pipeline& pipeline) {
  const PipelineConfig& c = pipeline.config();
  return c.detector.halve_whole_sweeps && c.filter.enabled && c.detector.track_edges &&
         !positions_from_centroids(c.positioning.mode) && pipeline.halved_sweep_suits();
}

// The scheduled check (Localizer::check_scheduled): the tracked pose is
// dropped when the whole sweep of the same frame gives none, or one the
// filter would refuse as a jump from it. Their errors are correlated (the
// same pixels, the same map), so the sum of their covariances overstates
// the difference's: a test for a track gone wrong, not for noise (on the
// unseen drives the two differ by chi-square 0.006-0.43, under 0.03 mm).
bool scheduled_check_agrees(const FilterParams& params, const PoseEstimate& tracked,
                            const PoseEstimate& whole) {
  if (!tracked.valid || !whole.valid) return false;
  const std::array<double, 3> d = {whole.pose.x_m - tracked.pose.x_m,
                                   whole.pose.y_m - tracked.pose.y_m,
                                   wrap_angle_rad(whole.pose.yaw_rad - tracked.pose.yaw_rad)};
  std::array<double, 9> s{}, s_inv{};
  for (size_t k = 0; k < s.size(); ++k) s[k] = tracked.covariance[k] + whole.covariance[k];
  return invert3(s, &s_inv) && !is_jump(params, d, s_inv);
}

}  // namespace

PipelineConfig with_mode(PipelineConfig config, PositioningMode mode, bool filter) {
  config.positioning.mode = mode;
  config.filter.enabled = filter;
  return config;
}

Localizer::Localizer(const PipelineConfig& config)
    : pipeline_(config),
      filter_(config.filter),
      view_(config),
      decoded_last_(static_cast<size_t>(view_.map().codes()) * view_.map().codes(), 0),
      result_(std::make_unique<FrameResult>()),
      check_result_(std::make_unique<FrameResult>()),
      halved_sweeps_(halved_sweeps(pipeline_)),
      planned_mount_(config.mount) {}

void Localizer::reconfigure(const PipelineConfig& config, bool reset_filter) {
  pipeline_.set_config(config);
  halved_sweeps_ = halved_sweeps(pipeline_);
  view_ = ViewGeometry(config);
  decoded_last_.assign(static_cast<size_t>(view_.map().codes()) * view_.map().codes(), 0);
  last_decoded_count_ = 0;
  frames_since_full_ = 0;
  decode_freed_tilt_ = false;  // another mount, perhaps
  planned_mount_ = config.mount;
  if (reset_filter) {
    filter_ = TemporalFilter(config.filter);
    forget_motion();
    had_fix_ = false;
  }
}

void Localizer::forget_motion() {
  filter_.reset();
  prediction_errors_.reset();
  extrapolation_errors_.reset();
  measured_count_ = 0;
  last_measured_ = false;
}

const Localization& Localizer::localize(const ImageView& image, const FrameInfo& frame) {
  const int64_t start_ns = monotonic_ns();
  check_due_ = false;  // the last frame's, if its caller did not run it
  // 1. The frame on its own.
  const PipelineConfig& config = pipeline_.config();
  const bool filter = config.filter.enabled;
  // The filter's state carried to this frame's time, once: for the
  // readout's motion and for the tracking windows.
  has_prediction_ = filter && predict_motion(filter_.motion(), frame.timestamp_ns, &predicted_) ==
                                  PredictOutcome::kOk;
  // Only a tracking plan chooses between the two (plan_sweep).
  has_extrapolation_ = false;
  if (filter && config.detector.tracking) extrapolate(frame.timestamp_ns);
  const CameraMotion motion = readout_motion();
  FullSweepReason sweep = plan_sweep();
  out_.swept_px = 0;
  out_.halved = false;
  bool decode_whole = false;  // a tracked sweep's edges alone freed the tilt
  if (sweep == FullSweepReason::kNone) {
    if (plan_.edges) {
      pipeline_.process_tracked(image, config.positioning.mode, result_.get(), motion,
                                plan_.predicted_span());
      decode_whole = edges_alone_freed_tilt(*result_);
    } else {
      pipeline_.process(image, config.positioning.mode, result_.get(), motion, plan_.span());
      remember_tilt_decision(*result_);
    }
    out_.swept_px = result_->swept_px;
    if (decode_whole || !tracked_sweep_held()) sweep = FullSweepReason::kTrackFailed;
  }
  if (sweep != FullSweepReason::kNone) {
    out_.halved = sweep_whole(image, motion, decode_whole, result_.get(), &out_.swept_px);
    sweeps_.halved += out_.halved ? 1 : 0;
    frames_since_full_ = 0;
    check_due_ = false;
  } else {
    ++frames_since_full_;
  }
  ++sweeps_.by_reason[static_cast<size_t>(sweep)];
  out_.sweep = sweep;
  out_.frame = frame;
  out_.measured = result_->estimate;
  out_.markers_decoded = result_->marker_count;
  out_.reconcile = result_->reconcile;
  out_.image = image;
  out_.detection = &pipeline_;
  out_.markers = std::span<const MarkerObservation>(result_->markers.data(),
                                                    static_cast<size_t>(result_->marker_count));
  out_.stage_ns = result_->stage_ns;
  // Nothing non-finite leaves the localizer, so no output (JSON, shared
  // memory, DDS) can carry it (issue 28: a map sigma of 1e154 gave valid
  // poses with a NaN covariance). Defence in depth: the inputs are bounded.
  if (out_.measured.valid && !finite_estimate(out_.measured)) {
    out_.measured.valid = false;
    out_.measured.refusal = Refusal::kSolverRejected;
  }

  // 2. Over time (the frame's own time, so processing jitter does not enter).
  out_.filtered = filter;
  out_.published = filter ? filter_.update(out_.measured, frame.timestamp_ns) : out_.measured;
  if (!out_.published.valid) {
    out_.published.refusal = out_.measured.valid ? Refusal::kFilterRejected : out_.measured.refusal;
  }
  out_.refusal = out_.measured.valid ? out_.published.refusal : out_.measured.refusal;
  out_.motion = filter && out_.published.valid ? filter_.motion() : MotionEstimate{};
  if (out_.published.valid && (!finite_estimate(out_.published) || !finite_motion(out_.motion))) {
    filter_.reset();  // a state that is not finite never becomes finite again
    out_.published = PoseEstimate{};
    out_.published.refusal = Refusal::kFilterRejected;
    out_.motion = MotionEstimate{};
    if (out_.measured.valid) out_.refusal = Refusal::kFilterRejected;
  }

  // 3. Fix state.
  if (out_.measured.valid && out_.published.valid) {
    had_fix_ = true;
    out_.fix = FixState::kOk;
  } else {
    out_.fix =
        out_.published.valid ? FixState::kCoasting : (had_fix_ ? FixState::kLost : FixState::kNone);
  }
  refusals_.count(out_.refusal);
  const bool last_measured_before = last_measured_;
  last_measured_ = out_.measured.valid;
  remember_decoded();
  remember_fitted_tilt();
  auto add_error = [&](const MotionState& s, PredictionErrors* errors) {
    errors->add(std::hypot(out_.measured.pose.x_m - s.x[0], out_.measured.pose.y_m - s.x[1]),
                wrap_angle_rad(out_.measured.pose.yaw_rad - s.x[2]));
  };
  if (has_prediction_ && last_measured_before && out_.measured.valid) {
    add_error(predicted_, &prediction_errors_);
  }
  if (has_extrapolation_ && out_.measured.valid) add_error(extrapolated_, &extrapolation_errors_);
  remember_measured(frame.timestamp_ns);
  out_.localize_ns = monotonic_ns() - start_ns;
  return out_;
}

CameraMotion Localizer::readout_motion() const {
  CameraMotion m;
  const PipelineConfig& c = pipeline_.config();
  if (!has_prediction_ || !(c.intrinsics.readout_ms > 0.0)) return m;
  const MotionState& s = predicted_;
  constexpr int N = kMotionStates;
  const double yaw = s.x[2], vx = s.x[3], vy = s.x[4], w = s.x[5];
  // The optical centre sits at R(yaw)·offset from the robot: it moves by
  // ω × that as well.
  double rx = 0.0, ry = 0.0;
  mount_offset_world(c.mount, yaw, &rx, &ry);
  const double sigma_w = std::sqrt(s.p[5 * N + 5]);
  m.valid = true;
  m.vx_mps = vx - w * ry;
  m.vy_mps = vy + w * rx;
  m.yaw_rate_radps = w;
  m.sigma_v_mps =
      std::sqrt(std::max(s.p[3 * N + 3], s.p[4 * N + 4])) + sigma_w * std::hypot(rx, ry);
  m.sigma_yaw_rate_radps = sigma_w;
  return m;
}

// The constant twist of the last two measurements (their chord's velocity
// turned to the tangent at the newer one) carried to t_ns.
void Localizer::extrapolate(int64_t t_ns) {
  has_extrapolation_ = false;
  if (measured_count_ < 2 || !last_measured_) return;
  const Measured& a = measured_[0];
  const Measured& b = measured_[1];
  const double dt1_s = 1e-9 * static_cast<double>(b.t_ns - a.t_ns);
  const double dt_s = 1e-9 * static_cast<double>(t_ns - b.t_ns);
  if (!(dt1_s > 0.0) || !(dt_s > 0.0)) return;
  const double w = wrap_angle_rad(b.yaw_rad - a.yaw_rad) / dt1_s;
  // A chord of a constant twist runs along the tangent at its middle.
  const double turn = 0.5 * w * dt1_s, c = std::cos(turn), s = std::sin(turn);
  const double cx = (b.x_m - a.x_m) / dt1_s, cy = (b.y_m - a.y_m) / dt1_s;
  const double vx = c * cx - s * cy, vy = s * cx + c * cy;
  double dx_m = 0.0, dy_m = 0.0;
  arc_displacement(vx, vy, w, dt_s, &dx_m, &dy_m);
  extrapolated_ = predicted_;
  extrapolated_.x[0] = b.x_m + dx_m;
  extrapolated_.x[1] = b.y_m + dy_m;
  extrapolated_.x[2] = wrap_angle_rad(b.yaw_rad + w * dt_s);
  const double c2 = std::cos(w * dt_s), s2 = std::sin(w * dt_s);
  extrapolated_.x[3] = c2 * vx - s2 * vy;
  extrapolated_.x[4] = s2 * vx + c2 * vy;
  extrapolated_.x[5] = w;
  for (int k = 6; k < kMotionStates; ++k) extrapolated_.x[k] = 0.0;
  has_extrapolation_ = std::isfinite(extrapolated_.x[0] + extrapolated_.x[1] + extrapolated_.x[2] +
                                     extrapolated_.x[3] + extrapolated_.x[4] + w);
}

void Localizer::remember_measured(int64_t t_ns) {
  if (!out_.measured.valid) {
    measured_count_ = 0;
    extrapolation_errors_.reset();
    return;
  }
  const Measured m{t_ns, out_.measured.pose.x_m, out_.measured.pose.y_m,
                   out_.measured.pose.yaw_rad};
  if (measured_count_ == 2) measured_[0] = measured_[1];
  measured_[std::min(measured_count_, 1)] = m;
  measured_count_ = std::min(measured_count_ + 1, 2);
}

FullSweepReason Localizer::plan_sweep() {
  const PipelineConfig& c = pipeline_.config();
  // Windows only from a prediction that the last frame's measurement
  // corrected (a coasting filter's prediction is not checked).
  const bool fix = has_prediction_ && last_measured_;
  if (!fix) prediction_errors_.reset();
  if (!c.detector.tracking || !c.filter.enabled) return FullSweepReason::kOff;
  if (!fix) return FullSweepReason::kNoFix;
  if (frames_since_full_ + 1 >= c.detector.full_sweep_every) {
    if (!defer_scheduled_) return FullSweepReason::kScheduled;
    check_due_ = true;  // tracked now, swept whole once published
  }
  const bool extrapolation_better = has_extrapolation_ && extrapolation_errors_.known() &&
                                    prediction_errors_.known() &&
                                    prediction_error_px(view_, extrapolation_errors_) <
                                        prediction_error_px(view_, prediction_errors_);
  if (extrapolation_better) {
    return plan_tracking(view_, planned_mount_, c.detector, c.positioning.mode, extrapolated_,
                         extrapolation_errors_, &plan_);
  }
  return plan_tracking(view_, planned_mount_, c.detector, c.positioning.mode, predicted_,
                       prediction_errors_, &plan_);
}

// A halved sweep stands when it gave a pose and measured at least two
// thirds of the pairs it found uncut. Under the stress levels, 1 frame of
// 16 had most of its markers blurred past their edges' profiles (2
// measured, 7 refused), which a full sweep's decode reads; a wide angle
// lens refuses 3-4 of 12 at its corners either way. Nor when its edges
// alone freed the tilt (edges_alone_freed_tilt).
bool Localizer::sweep_whole(const ImageView& image, const CameraMotion& motion, bool decode_whole,
                            FrameResult* r, int64_t* swept_px) {
  const PositioningMode mode = pipeline_.config().positioning.mode;
  bool halved = false;
  if (halved_sweeps_ && !decode_whole) {
    pipeline_.process_halved(image, mode, r, motion);
    *swept_px += r->swept_px;
    const MarkerRejects& rejects = r->rejects;
    halved = r->estimate.valid && r->marker_count >= 2 * (rejects.total() - rejects.cut) &&
             !edges_alone_freed_tilt(*r);
  }
  if (!halved) {
    pipeline_.process(image, mode, r, motion);
    *swept_px += r->swept_px;
    remember_tilt_decision(*r);
  }
  return halved;
}

void Localizer::check_scheduled(const ImageView& image) {
  if (!check_due_) return;
  check_due_ = false;
  frames_since_full_ = 0;
  int64_t swept_px = 0;
  sweep_whole(image, readout_motion(), false, check_result_.get(), &swept_px);
  ++sweeps_.checked;
  if (scheduled_check_agrees(pipeline_.config().filter, out_.measured, check_result_->estimate))
    return;
  ++sweeps_.check_failed;
  forget_motion();
}

// A tracked sweep stands only when it decoded again every marker the last
// frame decoded that the plan put wholly inside the frame (markers a whole
// sweep cannot decode either, at a wide-angle lens's corners, are not
// expected), cut no coloured blob at a window's side, was not abandoned as
// noise and gave a pose: otherwise the whole frame decides.
bool Localizer::tracked_sweep_held() const {
  const FrameResult& r = *result_;
  if (!r.estimate.valid || r.noisy || r.window_cuts != 0) return false;
  const int codes = view_.map().codes();
  for (int w = 0; w < plan_.expected_whole; ++w) {
    const int32_t index = plan_.whole[w];
    if (decoded_last_[static_cast<size_t>(index)] == 0) continue;
    bool found = false;
    for (int m = 0; m < r.marker_count && !found; ++m)
      found = r.markers[m].code_j * codes + r.markers[m].code_i == index;
    if (!found) return false;
  }
  return true;
}

// Edge points alone, measured along the pixel grid, share one sub-pixel
// phase per marker, and a renderer that quantises or mixes in sRGB biases
// each marker's edges its own way. On the patrol's level lane at yaw 0 the
// edge-tracked and halved sweeps' tilt chi-square was 13-34 (a free tilt at
// 33.8, 2.6 mm off) where the whole decode's, with the centroids, was
// 0.9-9.6. Such a frame is decoded whole, whose decision stands; once a
// whole decode has freed the tilt (a mount tilted past its calibration),
// edge points free it again on their own.
bool Localizer::edges_alone_freed_tilt(const FrameResult& r) const {
  const LsqResult* fit = last_fit(r);
  return !decode_freed_tilt_ && fit != nullptr && fit->tilt_choice == TiltChoice::kFreeFits;
}

void Localizer::remember_tilt_decision(const FrameResult& r) {
  const LsqResult* fit = last_fit(r);
  if (fit != nullptr && fit->tilt_choice != TiltChoice::kNotAllowed)
    decode_freed_tilt_ = fit->tilt_choice == TiltChoice::kFreeFits;
}

const LsqResult* Localizer::last_fit(const FrameResult& r) const {
  if (!r.estimate.valid || r.estimate.mode != PositioningMode::kLeastSquares) return nullptr;
  return &pipeline_.positioner().last_lsq();
}

// The pose the filter carries was fitted with this tilt: predicted with
// it, the markers fall where that fit saw them.
void Localizer::remember_fitted_tilt() {
  const LsqResult* fit = last_fit(*result_);
  if (fit == nullptr) return;
  const CameraMount& configured = pipeline_.config().mount;
  const bool freed = fit->tilt_estimated && std::isfinite(fit->tilt_x_rad + fit->tilt_y_rad);
  planned_mount_.tilt_x_rad = freed ? fit->tilt_x_rad : configured.tilt_x_rad;
  planned_mount_.tilt_y_rad = freed ? fit->tilt_y_rad : configured.tilt_y_rad;
}

void Localizer::remember_decoded() {
  for (int k = 0; k < last_decoded_count_; ++k)
    decoded_last_[static_cast<size_t>(last_decoded_[k])] = 0;
  last_decoded_count_ = 0;
  const int codes = view_.map().codes();
  for (int m = 0; m < result_->marker_count; ++m) {
    const MarkerObservation& o = result_->markers[m];
    if (o.code_i < 0 || o.code_j < 0 || o.code_i >= codes || o.code_j >= codes) continue;
    const int32_t index = o.code_j * codes + o.code_i;
    if (decoded_last_[static_cast<size_t>(index)] != 0) continue;
    decoded_last_[static_cast<size_t>(index)] = 1;
    last_decoded_[last_decoded_count_++] = index;
  }
}

}  // namespace ceilpose
