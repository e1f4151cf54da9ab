#pragma once
// What localizing one frame gives every consumer (shared memory, DDS, JSON
// Lines, accuracy scoring): the frame on its own, the pose to publish, the
// fix state and, when there is no pose, why.
#include <array>
#include <cstdint>
#include <span>

#include "core/fix_state.h"
#include "core/motion_model.h"
#include "core/pose.h"
#include "core/refusal.h"
#include "pipeline/marker_tracking.h"
#include "pipeline/pipeline.h"
#include "pipeline/pose_estimate.h"

namespace ceilpose {

// Where a frame came from, as far as the consumers care.
struct FrameInfo {
  int64_t timestamp_ns = 0;  // the frame's time (capture, or the recording's)
  int64_t index = -1;        // the recording's frame index, else -1
  bool has_ground_truth = false;
  Pose2D ground_truth;
};

struct Localization {
  FrameInfo frame;
  PoseEstimate measured;   // this frame solved on its own
  PoseEstimate published;  // what to publish: the filter's output, or `measured` unfiltered
  bool filtered = false;   // `published` came from the temporal filter
  // The filter's full state at the frame's time (valid with a valid filtered
  // pose): velocity, acceleration and what prediction needs.
  MotionEstimate motion;
  FixState fix = FixState::kNone;
  // Why this frame gave no measurement (kNone when it did; kFilterRejected
  // when it did but the filter refused it). published.refusal says why the
  // published pose is invalid: the same, or kNone while coasting.
  Refusal refusal = Refusal::kNone;
  int markers_decoded = 0;  // markers the pipeline decoded
  // Of those, how many the reconcile step believed, and why not the others.
  ReconcileCounts reconcile;
  // The decoded markers themselves (the survey's observations); valid until
  // the next frame is localized.
  std::span<const MarkerObservation> markers;
  // The frame and the detection's intermediate results (rectangles, pairs
  // and what became of each), for diagnostics such as `locate --annotate`;
  // valid until the next frame is localized.
  ImageView image;
  const Pipeline* detection = nullptr;
  // How the frame was swept: kNone tracked (windows only), else why whole
  // (a failed tracked sweep is followed by a whole one of the same frame).
  FullSweepReason sweep = FullSweepReason::kOff;
  // Swept whole, its markers found at half resolution (Localizer,
  // detector.halve_whole_sweeps); false when that gave no pose and the frame
  // was swept again at full resolution.
  bool halved = false;
  int64_t swept_px = 0;  // pixels classified, both sweeps of a failed track included
  std::array<int64_t, kStageCount> stage_ns{};  // duration of each pipeline stage
  int64_t localize_ns = 0;                      // whole localization, filter included

  bool coasting() const { return published.valid && !measured.valid; }
  bool tracked() const { return sweep == FullSweepReason::kNone; }
};

}  // namespace ceilpose
