#pragma once
// The marker localization pipeline of one camera: frame in, decoded markers
// and pose out, in numbered stages each followed by a time stamp, so that the
// per-stage cost is measured where it is spent.
// Not thread-safe: one instance per processing thread. process() allocates
// nothing, throws nothing and logs nothing; the result says what went wrong.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/image.h"
#include "pipeline/color_classifier.h"
#include "pipeline/components.h"
#include "pipeline/dot_reader.h"
#include "pipeline/marker_observation.h"
#include "pipeline/marker_pairing.h"
#include "pipeline/marker_tracking.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/pose_estimate.h"
#include "pipeline/positioner.h"
#include "pipeline/rectangle_ends.h"
#include "pipeline/rectangle_fit.h"

namespace ceilpose {

enum PipelineStage : int {
  kStageComponents = 0,  // classification, runs and connected components
  kStageRectangles,      // rectangle template fit
  kStagePairing,         // red/green pairing and heading
  kStageDecoding,        // dot reading, code and geometry checks, points
  kStageReconcile,       // which decoded markers to believe (Positioner::reconcile)
  kStagePositioning,     // Positioner::position
  kStageCount
};

// Rectangle pairs of one frame that were not decoded, by reason (each pair's
// own is its MarkerPair::outcome). They decide the frame's refusal when no
// marker decodes.
struct MarkerRejects {
  int cut = 0;           // touching the frame border
  int blurred = 0;       // blur along North too wide for the red dots
  int unreadable = 0;    // slots outside the frame
  int ambiguous = 0;     // a slot too close to the dot threshold
  int inconsistent = 0;  // dark area disagreeing with the code
  int overflow = 0;      // beyond kMaxMarkersPerFrame
  int total() const { return cut + blurred + unreadable + ambiguous + inconsistent + overflow; }
  void count(PairOutcome outcome) {
    switch (outcome) {
      case PairOutcome::kDecoded:
        break;
      case PairOutcome::kCut:
        ++cut;
        break;
      case PairOutcome::kBlurred:
        ++blurred;
        break;
      case PairOutcome::kUnreadable:
        ++unreadable;
        break;
      case PairOutcome::kAmbiguous:
        ++ambiguous;
        break;
      case PairOutcome::kInconsistent:
        ++inconsistent;
        break;
      case PairOutcome::kOverflow:
        ++overflow;
        break;
    }
  }
};

struct FrameResult {
  PoseEstimate estimate;  // estimate.refusal says why when invalid
  int marker_count = 0;
  std::array<MarkerObservation, kMaxMarkersPerFrame> markers{};
  MarkerRejects rejects;
  bool noisy = false;       // the labeler abandoned the frame (run budget exceeded)
  int window_cuts = 0;      // tracked: coloured blobs cut by a window edge (ComponentLabeler)
  int64_t swept_px = 0;     // pixels the labeler classified (the windows', or the frame's)
  bool unit_gains = false;  // no tile to take the colour reference from
  std::array<int64_t, kStageCount> stage_ns{};  // duration of each stage
  int64_t total_ns = 0;
  ReconcileCounts reconcile;  // which decoded markers were believed, why not the others
};

class Pipeline {
 public:
  // Preallocates every buffer for the configured image size. Throws
  // std::invalid_argument naming the field when the image size is not
  // positive.
  explicit Pipeline(const PipelineConfig& config);

  // Processes one frame. A frame of another size than the configured
  // intrinsics, compressed, empty or malformed, gives an invalid estimate
  // (refusal unusable_frame) and no markers.
  // `motion`: the camera's motion during the readout when known from
  // elsewhere (rolling shutter; see Positioner::solve).
  // `windows` (a tracked sweep, marker_tracking.h): label only there, merged
  // and inside the frame; empty: the whole frame.
  void process(const ImageView& frame, PositioningMode mode, FrameResult* out,
               const CameraMotion& motion = {}, std::span<const PixelWindow> windows = {});

  // A tracked frame measured where the prediction puts each marker (plan_tracking's
  // predicted markers, detector.track_edges): its edges and dots only, no
  // classification, no components (rectangles() and pairs() then stay
  // empty; components() keep the last sweep's). A marker
  // whose codes read otherwise than predicted is rejected as inconsistent.
  void process_tracked(const ImageView& frame, PositioningMode mode, FrameResult* out,
                       const CameraMotion& motion, std::span<const PredictedMarker> predicted);

  // A whole sweep that finds the markers at half resolution, or a quarter
  // where they are large (ComponentLabeler::label_sampled at
  // sweep_step_px(): 1/4 or 1/16 of the pixels classified) and
  // measures each at its edges and dots as an edge-tracked frame does, so
  // that it positions from the edges alone (a mode that positions from
  // centroids needs process()). For frames whose markers are large enough
  // (halved_sweep_suits).
  void process_halved(const ImageView& frame, PositioningMode mode, FrameResult* out,
                      const CameraMotion& motion);

  // Replaces the configuration (SIGHUP reload of thresholds); rebuilds the
  // colour table and re-allocates only if the image size changed. Not in the
  // per-frame path.
  void set_config(const PipelineConfig& config);

  // The configured camera sees a marker's red dots at least
  // kHalvedSweepMinDot_px tall from the nominal height: at half resolution
  // they still span samples enough to be folded into their rectangle.
  bool halved_sweep_suits() const;
  // The sampling step of a halved sweep: 2, or 4 where red dots are twice
  // kHalvedSweepMinDot_px tall (1280x960: 13 px) and still span 3 samples;
  // 1 where it does not suit.
  int sweep_step_px() const;

  static const char* stage_name(int stage);

  const PipelineConfig& config() const { return config_; }
  // Intermediate results of the last frame, for tests and diagnostics.
  std::span<const Component> components() const { return labeler_.components(); }
  std::span<const RectangleCandidate> rectangles() const { return {rects_.data(), rect_count_}; }
  std::span<const MarkerPair> pairs() const { return {pairs_.data(), pair_count_}; }
  // The last frame's positioning in detail (the least-squares solve, its tilt choice).
  const Positioner& positioner() const { return positioner_; }

 private:
  bool usable(const ImageView& frame) const;
  class StageClock;
  Refusal begin(const ImageView& frame, FrameResult* out);
  void position(PositioningMode mode, const CameraMotion& motion, FrameResult* out,
                StageClock* clock);
  PairOutcome read_codes(const ImageView& frame, const MarkerFrame& m,
                         const RectangleEdges& red_edges, DotSearch search, CodeReading* code_i,
                         CodeReading* code_j) const;
  PairOutcome decode(const ImageView& frame, const MarkerPair& pair, MarkerObservation* out);
  PairOutcome measure_at(const ImageView& frame, MarkerFrame m, MarkerObservation* out);
  PairOutcome measure_predicted(const ImageView& frame, const PredictedMarker& predicted,
                                MarkerObservation* out);
  PairOutcome measure_found(const ImageView& frame, const MarkerPair& pair, MarkerObservation* out);
  float pair_quality(const MarkerPair& pair) const;
  template <typename Decode>
  void finish_sweep(PositioningMode mode, const CameraMotion& motion, FrameResult* out,
                    StageClock* clock, Decode decode_pair);
  static Refusal refusal_without_markers(const FrameResult& result, size_t pair_count);

  PipelineConfig config_;
  ColorClassifier classifier_;
  ComponentLabeler labeler_;
  RectangleModel model_;
  std::vector<RectangleCandidate> rects_;
  size_t rect_count_ = 0;
  MarkerPairer pairer_;
  std::vector<MarkerPair> pairs_;
  size_t pair_count_ = 0;
  Positioner positioner_;
};

}  // namespace ceilpose
