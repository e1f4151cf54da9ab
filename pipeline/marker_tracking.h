#pragma once
// Tracking (issue 29): with a fix, where every marker will appear in the
// next frame, so that the labeler sweeps only there. The filter's pose
// predicted to the frame's time is projected through the camera model; each
// marker's window is its outline's box widened by a margin that grows with
// the prediction's uncertainty and the motion during the readout.
//
// The uncertainty is the one the predictions have shown, not the filter's
// covariance: on the drive set one frame ahead the filter's sd is 1.7 mm
// and 2.3° (its yaw jerk noise is sized for sudden turns), while its errors
// were 0.3 mm and 0.017° RMS (max 3.3 mm, 0.09°). Windows sized by the
// covariance covered the whole frame. A manoeuvre beyond the margin loses
// or cuts a marker, and the frame is swept again whole: it costs time, never
// a pose.
#include <array>
#include <cmath>
#include <span>

#include "core/motion_model.h"
#include "core/positioning_mode.h"
#include "core/view_geometry.h"
#include "pipeline/components.h"
#include "pipeline/detector_params.h"
#include "pipeline/dot_reader.h"
#include "pipeline/marker_observation.h"

namespace ceilpose {

// A marker the prediction puts wholly in the frame: its codes and the
// affine view of its frame there (at its own row's instant under a rolling
// shutter), where an edge-tracked frame measures its edges and reads its
// dots (detector.track_edges).
struct PredictedMarker {
  int code_i = 0, code_j = 0;
  MarkerFrame frame;
};

struct TrackingPlan {
  std::array<PixelWindow, kMaxMarkersPerFrame> windows{};
  int window_count = 0;
  // Markers whose outline lies inside the frame by the margin, as map
  // indices j * codes + i: one the last frame decoded and this tracked
  // sweep does not was not where its window looked.
  std::array<int32_t, kMaxMarkersPerFrame> whole{};
  int expected_whole = 0;
  // Edge-tracked (detector.track_edges, in a mode that positions from the
  // edges): the same markers where they will be (whole[k] is
  // predicted[k]'s), which the frame measures instead of sweeping windows;
  // none otherwise (no work a windows' sweep would not read).
  bool edges = false;
  std::array<PredictedMarker, kMaxMarkersPerFrame> predicted{};
  int predicted_count = 0;
  std::span<const PredictedMarker> predicted_span() const {
    return {predicted.data(), static_cast<size_t>(predicted_count)};
  }
  double margin_px = 0.0;
  std::span<const PixelWindow> span() const {
    return {windows.data(), static_cast<size_t>(window_count)};
  }
};

// The last one-frame-ahead prediction's errors. The last, not an average:
// after a sudden stop or a robot set down elsewhere the filter's
// predictions err by 100-250 mm for a few frames, then by tenths of a
// millimetre again, and an average remembered the transient for seconds.
// Nor the largest of the last three: a turn's start rings the filter for
// four or five frames, each error a third to a half of the one before, so
// the last error bounds the next within the margin's factor
// (track_margin_errors), and each older error remembered swept the patrol
// path whole once more at every turn (uncertain whole sweeps 11.7 % of
// its frames with three, 8.0 % with the last); a missed marker costs a
// second sweep, never a pose. The first predictions after the filter
// starts are left out: its velocity starts at zero, so they err by a
// frame's motion (27 mm at 0.8 m/s); and none sizes a margin until
// kSettling more were seen, over which its velocity settles.
class PredictionErrors {
 public:
  void add(double position_m, double yaw_rad);
  void reset() { *this = PredictionErrors{}; }
  // Enough predictions seen to size windows by.
  bool known() const { return samples_ >= kSkipped + kSettling; }
  double position_m() const { return position_m_; }
  double yaw_rad() const { return yaw_rad_; }

 private:
  static constexpr int kSkipped = 3;
  static constexpr int kSettling = 3;
  double position_m_ = 0.0, yaw_rad_ = 0.0;
  int samples_ = 0;
};

// Why a frame is swept whole rather than tracked (counted by the localizer).
enum class FullSweepReason : uint8_t {
  kNone,         // tracked
  kOff,          // detector.tracking false, or no filter
  kNoFix,        // no filter state at the frame's time, or the last frame had no measurement
  kScheduled,    // detector.full_sweep_every
  kUncertain,    // the windows would cover more than detector.track_max_area_share
  kTooMany,      // more markers in view than windows
  kTrackFailed,  // the tracked sweep lost a marker, cut one, or gave no pose: swept again
};
const char* to_string(FullSweepReason reason);

// How far off, pixels, a marker at the frame's corner may be when the next
// prediction errs as the last (`errors`) did: the position error times the
// ceiling's pixels a metre, plus the yaw error times the half diagonal.
// plan_tracking's margins grow with it; the localizer plans from whichever
// prediction makes it smaller.
double prediction_error_px(const ViewGeometry& view, const PredictionErrors& errors);

// Plans the windows (or, edge-tracked, the markers) for positioning `mode`
// and the robot state `s` (predicted to the frame's time; the
// camera's readout_ms widens them) whose predictions have erred by
// `errors`, seen by a camera on `mount` (the view's, or its tilt as the last
// fit freed it). Returns kNone and fills `plan`, or the reason to sweep the
// whole frame.
FullSweepReason plan_tracking(const ViewGeometry& view, const CameraMount& mount,
                              const DetectorParams& params, PositioningMode mode,
                              const MotionState& s, const PredictionErrors& errors,
                              TrackingPlan* plan);

}  // namespace ceilpose
