#include "pipeline/pipeline.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "core/clock.h"
#include "core/length_2d.h"
#include "core/pixel_read.h"
#include "pipeline/dot_reader.h"
#include "pipeline/rectangle_ends.h"

namespace ceilpose {
namespace {

// Rectangles kept per frame: 9–12 markers give ~24; the rest is headroom
// for clutter.
constexpr int kMaxRectangles = 256;
// How far an edge-tracked marker may lie from its prediction, pixels, before
// its edges are measured again around where they were found.
constexpr double kRecentreEdges_px = 1.0;
// Smallest red dot, pixels at the nominal height, for a halved sweep: 2.5
// samples at half resolution (a 640x480 frame's are 6-7 px, a 320x240
// one's 3 px).
constexpr double kHalvedSweepMinDot_px = 5.0;

void check_size(const CameraIntrinsics& k) {
  if (k.width <= 0 || k.height <= 0) {
    throw std::invalid_argument("pipeline: camera.width and camera.height must be positive, got " +
                                std::to_string(k.width) + "x" + std::to_string(k.height));
  }
}

}  // namespace

Pipeline::Pipeline(const PipelineConfig& config)
    : config_(config),
      classifier_(config.detector, config.layout.tile),
      labeler_(config.intrinsics.width, config.intrinsics.height, config.detector),
      model_(make_rectangle_model(config.intrinsics, config.mount, config.layout)),
      rects_(kMaxRectangles),
      pairer_(kMaxRectangles),
      pairs_(kMaxMarkersPerFrame),
      positioner_(config) {
  check_size(config.intrinsics);
}

void Pipeline::set_config(const PipelineConfig& config) {
  check_size(config.intrinsics);
  config_ = config;
  classifier_.set_params(config.detector, config.layout.tile);
  // The run budget depends on the parameters as well as on the size.
  labeler_ = ComponentLabeler(config.intrinsics.width, config.intrinsics.height, config.detector);
  model_ = make_rectangle_model(config.intrinsics, config.mount, config.layout);
  positioner_ = Positioner(config);
}

int Pipeline::sweep_step_px() const {
  const double red_dot_px = model_.px_per_m * config_.layout.red_dot_n_m;
  return red_dot_px >= 2.0 * kHalvedSweepMinDot_px ? 4
         : red_dot_px >= kHalvedSweepMinDot_px     ? 2
                                                   : 1;
}

bool Pipeline::halved_sweep_suits() const { return sweep_step_px() > 1; }

const char* Pipeline::stage_name(int stage) {
  switch (stage) {
    case kStageComponents:
      return "components";
    case kStageRectangles:
      return "rectangles";
    case kStagePairing:
      return "pairing";
    case kStageDecoding:
      return "decoding";
    case kStageReconcile:
      return "reconcile";
    case kStagePositioning:
      return "positioning";
    default:
      return "unknown";
  }
}

bool Pipeline::usable(const ImageView& frame) const {
  if (frame.empty() || frame.format == PixelFormat::kMjpeg) return false;
  if (frame.width != config_.intrinsics.width || frame.height != config_.intrinsics.height)
    return false;
  const size_t row_bytes = static_cast<size_t>(frame.width) * bytes_per_pixel(frame.format);
  if (frame.stride_bytes < 0 || static_cast<size_t>(frame.stride_bytes) < row_bytes) return false;
  if (is_yuv420(frame.format)) {
    // Chroma pairs need an even width; the chroma planes follow the luma.
    if (frame.width % 2 != 0 || frame.stride_bytes % 2 != 0) return false;
    return frame.size_bytes == 0 ||
           frame.size_bytes >= frame_bytes(frame.format, frame.stride_bytes, frame.height);
  }
  const size_t needed = static_cast<size_t>(frame.stride_bytes) * (frame.height - 1) + row_bytes;
  return frame.size_bytes == 0 || frame.size_bytes >= needed;
}

// Blur, then the dots: the part of decoding that needs only the marker's
// frame and its red rectangle's edges (a whole sweep's decode and an
// edge-tracked frame's alike).
PairOutcome Pipeline::read_codes(const ImageView& frame, const MarkerFrame& m,
                                 const RectangleEdges& red_edges, DotSearch search,
                                 CodeReading* code_i, CodeReading* code_j) const {
  const CeilingLayout& layout = config_.layout;
  // Blur first: it decides whether the dots can be read and where their
  // threshold lies.
  const double red_dot_px = layout.red_dot_n_m * length_2d(m.north_u, m.north_v);
  const double blur_px = red_edges.spread_px;
  if (blur_px > config_.detector.max_blur_to_dot * red_dot_px) return PairOutcome::kBlurred;
  const float threshold = dot_threshold_ratio(config_.detector, blur_px, red_dot_px);
  *code_i = read_code(frame, m, true, layout, config_.detector, threshold, search);
  *code_j = read_code(frame, m, false, layout, config_.detector, threshold, search);
  if (!code_i->ok || !code_j->ok) return PairOutcome::kUnreadable;
  if (std::min(code_i->margin, code_j->margin) < config_.detector.dot_min_margin)
    return PairOutcome::kAmbiguous;
  if (code_i->code >= layout.codes() || code_j->code >= layout.codes())
    return PairOutcome::kInconsistent;
  return PairOutcome::kDecoded;
}

namespace {

// The rectangles' edges around the marker as its points for positioning:
// what lets a fit tell a tilt from a shift marker by marker
// (rectangle_ends.h). Each is measured across its edge only.
// Calls fn with every edge crossing found on both rectangles: ends, then
// long sides, red first.
template <typename Fn>
void for_each_crossing(const RectangleEdges& red_edges, const RectangleEdges& green_edges, Fn fn) {
  for (const RectangleEdges* edges : {&red_edges, &green_edges}) {
    for (const EdgeCrossing& c : edges->end)
      if (c.found) fn(c);
    for (int k = 0; k < edges->side_count; ++k)
      if (edges->side[static_cast<size_t>(k)].found) fn(edges->side[static_cast<size_t>(k)]);
  }
}

void add_edge_points(const RectangleEdges& red_edges, const RectangleEdges& green_edges,
                     MarkerObservation* o) {
  for_each_crossing(red_edges, green_edges, [&](const EdgeCrossing& c) {
    if (o->point_count == kMaxPointsPerMarker) return;
    o->points[o->point_count++] = {c.e_m, c.n_m, c.u_px, c.v_px, c.normal_u, c.normal_v};
  });
}

// How far the rectangles' edges lie from where `m` put them, as one image
// translation (du, dv), pixels: least squares over every edge's displacement
// across itself. Opposite edges move opposite ways under the edge offset, so
// it cancels. False when the edges found do not fix both directions.
bool edge_shift_px(const MarkerFrame& m, const RectangleEdges& red_edges,
                   const RectangleEdges& green_edges, double* du, double* dv) {
  double a00 = 0.0, a01 = 0.0, a11 = 0.0, b0 = 0.0, b1 = 0.0;
  for_each_crossing(red_edges, green_edges, [&](const EdgeCrossing& c) {
    double u = 0.0, v = 0.0;
    m.project(c.e_m, c.n_m, &u, &v);
    const double d = (c.u_px - u) * c.normal_u + (c.v_px - v) * c.normal_v;
    a00 += c.normal_u * c.normal_u;
    a01 += c.normal_u * c.normal_v;
    a11 += c.normal_v * c.normal_v;
    b0 += c.normal_u * d;
    b1 += c.normal_v * d;
  });
  const double det = a00 * a11 - a01 * a01;
  if (!(det > 0.25)) return false;  // e.g. the ends alone: nothing across the long sides
  *du = (a11 * b0 - a01 * b1) / det;
  *dv = (a00 * b1 - a01 * b0) / det;
  return true;
}

// The marker-frame rectangle an edge measurement reads: the outline and
// the reach of its edges' profiles.
double measured_half_e_m(const CeilingLayout& layout) {
  return layout.rect_width_m + kEdgeProfileHalf_m;
}
double measured_half_n_m(const CeilingLayout& layout) {
  return 0.5 * layout.rect_height_m + kEdgeProfileHalf_m;
}

// Whole: the marker's outline's corners project inside the frame.
bool outline_inside(const ImageView& frame, const MarkerFrame& m, const CeilingLayout& layout) {
  const double half_e_m = layout.rect_width_m, half_n_m = 0.5 * layout.rect_height_m;
  for (double se : {-1.0, 1.0}) {
    for (double sn : {-1.0, 1.0}) {
      double u = 0.0, v = 0.0;
      m.project(se * half_e_m, sn * half_n_m, &u, &v);
      if (!(u >= 0.0 && v >= 0.0 && u <= frame.width - 1.0 && v <= frame.height - 1.0))
        return false;
    }
  }
  return true;
}

}  // namespace

float Pipeline::pair_quality(const MarkerPair& pair) const {
  return std::clamp(
      1.0f - static_cast<float>(pair.score) / config_.detector.quality_zero_pair_score, 0.0f, 1.0f);
}

PairOutcome Pipeline::decode(const ImageView& frame, const MarkerPair& pair,
                             MarkerObservation* out) {
  const RectangleCandidate& red = rects_[pair.red];
  const RectangleCandidate& green = rects_[pair.green];
  // A rectangle cut by the frame border has a shifted centroid, which puts
  // the slots off the dots: such a marker could only be misread.
  if (red.touches_border || green.touches_border) {
    return PairOutcome::kCut;
  }
  const CeilingLayout& layout = config_.layout;
  const MarkerFrame m = marker_frame(red, green, layout);
  const double px_per_m = length_2d(m.north_u, m.north_v);
  const RectangleEdges red_edges = measure_edges(frame, m, true, layout);
  CodeReading code_i, code_j;
  const PairOutcome read =
      read_codes(frame, m, red_edges, DotSearch::kFromCentroids, &code_i, &code_j);
  if (read != PairOutcome::kDecoded) return read;
  if (!dark_area_consistent(red, code_i.code, true, layout, px_per_m) ||
      !dark_area_consistent(green, code_j.code, false, layout, px_per_m)) {
    return PairOutcome::kInconsistent;
  }
  MarkerObservation& o = *out;
  o.code_i = code_i.code;
  o.code_j = code_j.code;
  o.centre_u_px = m.centre_u_px;
  o.centre_v_px = m.centre_v_px;
  o.red_u_px = red.cx;
  o.red_v_px = red.cy;
  o.green_u_px = green.cx;
  o.green_v_px = green.cy;
  o.west_image_rad = m.west_image_rad;
  o.whole = outline_inside(frame, m, layout);
  const float margin = std::min(code_i.margin, code_j.margin);
  o.quality =
      std::clamp(margin / config_.detector.quality_full_margin, 0.0f, 1.0f) * pair_quality(pair);
  // Points for positioning: the centroids. Area centroids of the full
  // rectangles (dots folded in) are unbiased under the affine view of a level
  // camera, thresholding shifts opposite edges alike, and fit_rectangles has
  // already removed the shift that lens distortion gives them.
  o.point_count = 0;
  o.points[o.point_count++] = {0.0, 0.0, m.centre_u_px, m.centre_v_px};
  o.points[o.point_count++] = {layout.red_centre_e_m(), 0.0, red.cx, red.cy};
  o.points[o.point_count++] = {layout.green_centre_e_m(), 0.0, green.cx, green.cy};
  add_edge_points(red_edges, measure_edges(frame, m, false, layout), &o);
  return PairOutcome::kDecoded;
}

// A marker measured at its edges and dots around `m`, where a prediction or
// a halved sweep's centroids put it: its codes are whatever the dots read
// (callers check them). Its rectangles' centres are midway between their
// measured ends (where `m` put them when an end was not measured: they seed
// the fit and the consistency check, the edge points alone position).
PairOutcome Pipeline::measure_at(const ImageView& frame, MarkerFrame m, MarkerObservation* out) {
  const CeilingLayout& layout = config_.layout;
  RectangleEdges red_edges = measure_edges(frame, m, true, layout, EdgeLevels::kLinearLight);
  RectangleEdges green_edges = measure_edges(frame, m, false, layout, EdgeLevels::kLinearLight);
  // A profile measures its edge truly only near its middle: one that
  // crosses it off-centre takes part of the blurred rise (or a dot) for a
  // plateau. When the marker lies more than kRecentreEdges_px from `m`
  // (a robot setting off from a pause: 4 px, 0.5 mm off), the edges are
  // measured again around where they were found.
  // Its edges must fix it both ways: ends alone leave it free along East,
  // where nothing but `m` would then place it (a prediction 8 px off put
  // the pose 32 mm off, valid). Measured again, they must lie where they
  // were found: otherwise the first profiles found something else. Either
  // way the marker is refused rather than positioned with.
  double du = 0.0, dv = 0.0;
  if (!edge_shift_px(m, red_edges, green_edges, &du, &dv)) return PairOutcome::kInconsistent;
  if (length_2d(du, dv) > kRecentreEdges_px) {
    m.centre_u_px += du;
    m.centre_v_px += dv;
    red_edges = measure_edges(frame, m, true, layout, EdgeLevels::kLinearLight);
    green_edges = measure_edges(frame, m, false, layout, EdgeLevels::kLinearLight);
    if (!edge_shift_px(m, red_edges, green_edges, &du, &dv) ||
        length_2d(du, dv) > kRecentreEdges_px)
      return PairOutcome::kInconsistent;
  }
  // The dots are then where the edges put them, to a pixel (DotSearch::
  // kFromEdges).
  CodeReading code_i, code_j;
  const PairOutcome read = read_codes(frame, m, red_edges, DotSearch::kFromEdges, &code_i, &code_j);
  if (read != PairOutcome::kDecoded) return read;
  MarkerObservation& o = *out;
  o.code_i = code_i.code;
  o.code_j = code_j.code;
  auto centre = [&](const RectangleEdges& edges, double e_m, double* u_px, double* v_px) {
    if (edges.end[0].found && edges.end[1].found) {
      *u_px = 0.5 * (edges.end[0].u_px + edges.end[1].u_px);
      *v_px = 0.5 * (edges.end[0].v_px + edges.end[1].v_px);
    } else {
      m.project(e_m, 0.0, u_px, v_px);
    }
  };
  centre(red_edges, layout.red_centre_e_m(), &o.red_u_px, &o.red_v_px);
  centre(green_edges, layout.green_centre_e_m(), &o.green_u_px, &o.green_v_px);
  o.centre_u_px = 0.5 * (o.red_u_px + o.green_u_px);
  o.centre_v_px = 0.5 * (o.red_v_px + o.green_v_px);
  o.west_image_rad = std::atan2(o.green_v_px - o.red_v_px, o.green_u_px - o.red_u_px);
  o.whole = true;  // the plan's (inside by the margin); a halved sweep's: its own check
  o.quality = std::clamp(
      std::min(code_i.margin, code_j.margin) / config_.detector.quality_full_margin, 0.0f, 1.0f);
  o.point_count = 0;
  add_edge_points(red_edges, green_edges, &o);
  return PairOutcome::kDecoded;
}

// An edge-tracked marker: the codes read must be the predicted ones.
PairOutcome Pipeline::measure_predicted(const ImageView& frame, const PredictedMarker& predicted,
                                        MarkerObservation* out) {
  const PairOutcome outcome = measure_at(frame, predicted.frame, out);
  if (outcome != PairOutcome::kDecoded) return outcome;
  if (out->code_i != predicted.code_i || out->code_j != predicted.code_j)
    return PairOutcome::kInconsistent;
  return outcome;
}

// A marker a halved sweep found: measured at its edges and dots as a
// tracked one is, around where its centroids put it, and held to what a
// whole sweep's decode checks (uncut, codes on the map's grid and agreeing
// with the dark area, the pair's score in its quality).
PairOutcome Pipeline::measure_found(const ImageView& frame, const MarkerPair& pair,
                                    MarkerObservation* out) {
  const RectangleCandidate& red = rects_[pair.red];
  const RectangleCandidate& green = rects_[pair.green];
  if (red.touches_border || green.touches_border) return PairOutcome::kCut;
  const CeilingLayout& layout = config_.layout;
  const MarkerFrame m = marker_frame(red, green, layout);
  const PairOutcome outcome = measure_at(frame, m, out);
  if (outcome != PairOutcome::kDecoded) return outcome;
  const double px_per_m = length_2d(m.north_u, m.north_v);
  if (!dark_area_consistent(red, out->code_i, true, layout, px_per_m) ||
      !dark_area_consistent(green, out->code_j, false, layout, px_per_m))
    return PairOutcome::kInconsistent;
  out->whole = outline_inside(frame, m, layout);
  out->quality *= pair_quality(pair);
  return outcome;
}

// With no marker decoded, the frame is refused for what stopped the pairs it
// had: none at all, only codes contradicting the dark area, or unreadable.
Refusal Pipeline::refusal_without_markers(const FrameResult& result, size_t pair_count) {
  if (pair_count == 0) return result.noisy ? Refusal::kNoisyFrame : Refusal::kNoMarkers;
  const MarkerRejects& r = result.rejects;
  if (r.inconsistent > 0 && r.inconsistent == r.total()) return Refusal::kInconsistentMarkers;
  return Refusal::kUnreadableMarkers;
}

// Stage laps of one frame into out->stage_ns.
class Pipeline::StageClock {
 public:
  explicit StageClock(FrameResult* out)
      : out_(out), start_ns_(monotonic_ns()), stamp_ns_(start_ns_) {}
  void lap(int stage) {
    const int64_t now_ns = monotonic_ns();
    out_->stage_ns[stage] = now_ns - stamp_ns_;
    stamp_ns_ = now_ns;
  }
  // The whole: the sum of the laps when there were any (a refused frame
  // has none).
  void finish() {
    out_->total_ns = (stamp_ns_ == start_ns_ ? monotonic_ns() : stamp_ns_) - start_ns_;
  }

 private:
  FrameResult* out_;
  int64_t start_ns_, stamp_ns_;
};

// The frame's result emptied; the frame's refusal when it cannot be used.
// SPEC §4 allows greyscale recordings (a checkerboard's), but the markers
// are red and green: such a frame is refused for what it lacks, not
// searched in vain for rectangles.
Refusal Pipeline::begin(const ImageView& frame, FrameResult* out) {
  out->estimate = PoseEstimate{};
  out->marker_count = 0;
  out->rejects = MarkerRejects{};
  out->noisy = false;
  out->window_cuts = 0;
  out->swept_px = 0;
  out->unit_gains = false;
  out->stage_ns.fill(0);
  out->reconcile = ReconcileCounts{};
  rect_count_ = 0;
  pair_count_ = 0;
  const Refusal unusable = !usable(frame)                        ? Refusal::kUnusableFrame
                           : frame.format == PixelFormat::kGray8 ? Refusal::kNoColour
                                                                 : Refusal::kNone;
  if (unusable != Refusal::kNone) out->estimate = refused_estimate(unusable);
  return unusable;
}

// 5. Reconcile: which decoded markers to believe; 6. positioning.
void Pipeline::position(PositioningMode mode, const CameraMotion& motion, FrameResult* out,
                        StageClock* clock) {
  const std::span<const MarkerObservation> decoded(out->markers.data(), out->marker_count);
  if (out->marker_count > 0) positioner_.reconcile(decoded, motion);
  clock->lap(kStageReconcile);
  if (out->marker_count == 0) {
    out->estimate = refused_estimate(refusal_without_markers(*out, pair_count_));
    out->reconcile = ReconcileCounts{};
  } else {
    out->estimate = positioner_.position(decoded, mode, motion);
    out->reconcile = positioner_.reconcile_counts();
  }
  clock->lap(kStagePositioning);
  clock->finish();
}

// 2. Rectangle template fit; 3. pairing, the red→green vector is West; 4.
// each pair decoded by `decode_pair`; then reconcile and positioning.
template <typename Decode>
void Pipeline::finish_sweep(PositioningMode mode, const CameraMotion& motion, FrameResult* out,
                            StageClock* clock, Decode decode_pair) {
  rect_count_ =
      static_cast<size_t>(fit_rectangles(labeler_.components(), model_, config_.detector, rects_));
  clock->lap(kStageRectangles);
  pair_count_ =
      static_cast<size_t>(pairer_.pair(rectangles(), config_.layout, config_.detector, pairs_));
  clock->lap(kStagePairing);
  for (size_t k = 0; k < pair_count_; ++k) {
    PairOutcome& outcome = pairs_[k].outcome;
    outcome = out->marker_count == kMaxMarkersPerFrame
                  ? PairOutcome::kOverflow
                  : decode_pair(k, &out->markers[out->marker_count]);
    out->rejects.count(outcome);
    if (outcome == PairOutcome::kDecoded) ++out->marker_count;
  }
  clock->lap(kStageDecoding);
  position(mode, motion, out, clock);
}

void Pipeline::process(const ImageView& frame, PositioningMode mode, FrameResult* out,
                       const CameraMotion& motion, std::span<const PixelWindow> windows) {
  StageClock clock(out);
  if (begin(frame, out) != Refusal::kNone) return clock.finish();

  // 1. Classify every pixel (adaptive fused lookup) and build components.
  out->unit_gains = !classifier_.adapt(frame);
  out->noisy = windows.empty() ? !labeler_.label(frame, classifier_)
                               : !labeler_.label(frame, classifier_, windows);
  out->window_cuts = labeler_.window_cut_count();
  out->swept_px = labeler_.swept_px();
  clock.lap(kStageComponents);
  finish_sweep(mode, motion, out, &clock,
               [&](size_t k, MarkerObservation* o) { return decode(frame, pairs_[k], o); });
}

void Pipeline::process_halved(const ImageView& frame, PositioningMode mode, FrameResult* out,
                              const CameraMotion& motion) {
  StageClock clock(out);
  if (begin(frame, out) != Refusal::kNone) return clock.finish();
  out->unit_gains = !classifier_.adapt(frame);
  out->noisy = !labeler_.label_sampled(frame, classifier_, sweep_step_px());
  out->swept_px = labeler_.swept_px();
  clock.lap(kStageComponents);
  const double half_e_m = measured_half_e_m(config_.layout);
  const double half_n_m = measured_half_n_m(config_.layout);
  // Half the rows were read: each marker's image is asked for one marker
  // ahead of its measuring, as a tracked frame's is.
  auto ask = [&](size_t k) {
    if (k >= pair_count_) return;
    const MarkerFrame m =
        marker_frame(rects_[pairs_[k].red], rects_[pairs_[k].green], config_.layout);
    ask_marker_region(frame, m, -half_e_m, half_e_m, -half_n_m, half_n_m);
  };
  finish_sweep(mode, motion, out, &clock, [&](size_t k, MarkerObservation* o) {
    if (k == 0) ask(0);
    ask(k + 1);
    return measure_found(frame, pairs_[k], o);
  });
}

void Pipeline::process_tracked(const ImageView& frame, PositioningMode mode, FrameResult* out,
                               const CameraMotion& motion,
                               std::span<const PredictedMarker> predicted) {
  StageClock clock(out);
  if (begin(frame, out) != Refusal::kNone) return clock.finish();
  // Nothing swept the frame: it is in memory, not in cache. Each marker's
  // image, with the reach of its edges' profiles, is asked for one marker
  // ahead of its reading: row by row only its span, since DRAM's cost
  // follows the rows more than their length (a tracked 640×480 frame's
  // reading 17–22 % cheaper than asking for a square around the marker,
  // docs/pipeline_speed.md).
  const double half_e_m = measured_half_e_m(config_.layout);
  const double half_n_m = measured_half_n_m(config_.layout);
  auto ask = [&](size_t k) {
    if (k < predicted.size())
      ask_marker_region(frame, predicted[k].frame, -half_e_m, half_e_m, -half_n_m, half_n_m);
  };
  ask(0);
  for (size_t k = 0; k < predicted.size(); ++k) {
    ask(k + 1);
    const PairOutcome outcome =
        out->marker_count == kMaxMarkersPerFrame
            ? PairOutcome::kOverflow
            : measure_predicted(frame, predicted[k], &out->markers[out->marker_count]);
    out->rejects.count(outcome);
    if (outcome == PairOutcome::kDecoded) ++out->marker_count;
  }
  clock.lap(kStageDecoding);
  position(mode, motion, out, &clock);
}

}  // namespace ceilpose
