#pragma once
// The marker localization pipeline of one camera: frame in, decoded markers
// and pose out, in numbered stages each followed by a time stamp (issue 3).
// Not thread-safe: one instance per processing thread. process() allocates
// nothing, throws nothing and logs nothing; it counts what went wrong.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/image.h"
#include "pipeline/color_classifier.h"
#include "pipeline/components.h"
#include "pipeline/marker_observation.h"
#include "pipeline/marker_pairing.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/pose_estimate.h"
#include "pipeline/positioner.h"
#include "pipeline/rectangle_fit.h"

namespace ceilpose {

enum PipelineStage : int {
  kStageComponents = 0,  // classification, runs and connected components
  kStageRectangles,      // rectangle template fit
  kStagePairing,         // red/green pairing and heading
  kStageDecoding,        // dot reading, code and geometry checks, points
  kStagePositioning,     // Positioner::solve
  kStageCount
};

struct FrameResult {
  PoseEstimate estimate;
  int marker_count = 0;
  std::array<MarkerObservation, kMaxMarkersPerFrame> markers{};
  std::array<int64_t, kStageCount> stage_ns{};  // duration of each stage
  int64_t total_ns = 0;
};

// What the pipeline rejected and why, since its start (never reset).
struct PipelineCounters {
  uint64_t frames = 0;
  uint64_t unusable_frames = 0;       // empty, wrong size or format, bad stride
  uint64_t run_budget_exceeded = 0;   // frames abandoned as noise
  uint64_t white_reference_kept = 0;  // frames without enough tile to adapt to
  uint64_t cut_markers = 0;           // pairs touching the frame border, not decoded
  uint64_t unreadable_codes = 0;      // pairs whose slots fell outside the frame
  uint64_t ambiguous_codes = 0;       // a slot too close to the dot threshold
  uint64_t blurred_markers = 0;       // blur along North too wide for the red dots
  uint64_t inconsistent_markers = 0;  // dark area disagreeing with the code
  uint64_t marker_overflow = 0;       // frames with more than kMaxMarkersPerFrame
};

class Pipeline {
 public:
  // Preallocates every buffer for the configured image size. Throws
  // std::invalid_argument naming the field when the image size is not
  // positive.
  explicit Pipeline(const PipelineConfig& config);

  // Processes one frame. A frame of another size than the configured
  // intrinsics, compressed, empty or malformed, gives an invalid estimate
  // and no markers.
  void process(const ImageView& frame, PositioningMode mode, FrameResult* out);

  // Replaces the configuration (SIGHUP reload of thresholds); rebuilds the
  // colour table and re-allocates only if the image size changed. Not in the
  // per-frame path.
  void set_config(const PipelineConfig& config);

  static const char* stage_name(int stage);

  const PipelineConfig& config() const { return config_; }
  const PipelineCounters& counters() const { return counters_; }
  const ColorClassifier& classifier() const { return classifier_; }
  // Intermediate results of the last frame, for tests and diagnostics.
  std::span<const Component> components() const { return labeler_.components(); }
  std::span<const RectangleCandidate> rectangles() const { return {rects_.data(), rect_count_}; }
  std::span<const MarkerPair> pairs() const { return {pairs_.data(), pair_count_}; }

 private:
  bool usable(const ImageView& frame) const;
  bool decode(const ImageView& frame, const MarkerPair& pair, MarkerObservation* out);

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
  PipelineCounters counters_;
};

}  // namespace ceilpose
