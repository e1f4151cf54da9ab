#pragma once
// The one path of a frame: pipeline (detection and positioning), temporal
// filter and fix state, for the daemon, `locate`/`evaluate`, the accuracy
// tests and the benchmarks alike. Counts every frame's refusal.
//
// Not thread-safe: one instance, called in frame order from one thread;
// refusals() may be read from any thread. localize() allocates nothing,
// throws nothing and logs nothing.
#include <array>
#include <memory>
#include <vector>

#include "core/refusal.h"
#include "core/view_geometry.h"
#include "pipeline/localization.h"
#include "pipeline/pipeline.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/temporal_filter.h"

namespace ceilpose {

// Frames swept by windows (tracked) and whole, by reason (FullSweepReason).
struct SweepCounts {
  std::array<uint64_t, 7> by_reason{};  // index: FullSweepReason
  uint64_t halved = 0;                  // of the whole ones: found at half resolution
  // Scheduled whole sweeps run after publishing (Localizer::check_scheduled),
  // and of those, how many disagreed with the tracked pose of their frame.
  uint64_t checked = 0;
  uint64_t check_failed = 0;
  uint64_t tracked() const { return by_reason[0]; }
  uint64_t full() const {
    uint64_t n = 0;
    for (size_t k = 1; k < by_reason.size(); ++k) n += by_reason[k];
    return n;
  }
};

// `config` with the positioning mode and the filter switch set, as `locate
// --mode --filter` and the tests choose them.
PipelineConfig with_mode(PipelineConfig config, PositioningMode mode, bool filter);

class Localizer {
 public:
  // Throws std::invalid_argument (from Pipeline) on a non-positive image size.
  // The mode is config.positioning.mode, the filter on when config.filter.enabled.
  explicit Localizer(const PipelineConfig& config);

  // Localizes one frame taken at frame.timestamp_ns (monotonic order). The
  // result stays valid until the next call.
  const Localization& localize(const ImageView& image, const FrameInfo& frame);

  // The scheduled whole sweep (detector.full_sweep_every) after publishing:
  // with this on, a frame due for it is tracked like any other, and
  // check_due() says the caller should call check_scheduled() with the same
  // image once the pose is out (the daemon, `locate`). Off, the scheduled
  // frame is swept whole before its pose (the tests, the benchmarks).
  void defer_scheduled_sweeps(bool on) { defer_scheduled_ = on; }
  bool check_due() const { return check_due_; }
  // Sweeps the last frame whole (`image` must be the one localize() was
  // given) and compares its pose with the tracked one. When the whole sweep
  // gives no pose, or one the filter would refuse as a jump from the
  // tracked one (is_jump), the fix is dropped: the filter restarts and
  // the next frame is swept whole. The last Localization's figures stay as
  // they were; its `detection` (the pipeline's state) then shows this sweep,
  // so a caller reads it before.
  void check_scheduled(const ImageView& image);

  // Between frames (SIGHUP): new tuning, mode and filter switch; the filter's
  // state is kept unless `reset_filter`.
  void reconfigure(const PipelineConfig& config, bool reset_filter);

  const PipelineConfig& config() const { return pipeline_.config(); }
  const RefusalHistogram& refusals() const { return refusals_; }
  const FilterStats& filter_stats() const { return filter_.stats(); }
  const SweepCounts& sweeps() const { return sweeps_; }
  // The last frame's detection in detail (markers, rejects), for diagnostics.
  const FrameResult& last_frame() const { return *result_; }
  const Pipeline& pipeline() const { return pipeline_; }

 private:
  Pipeline pipeline_;
  TemporalFilter filter_;
  ViewGeometry view_;  // for the tracking windows
  TrackingPlan plan_;
  MotionState predicted_;        // the filter's state carried to this frame's time
  bool has_prediction_ = false;  // ... when there was one
  PredictionErrors prediction_errors_;
  // A second prediction for the tracking plan alone: the last two
  // consecutive measurements' motion carried on as a constant twist. After
  // a sudden turn it is right again a frame after the turn's start, while
  // the filter (constant acceleration) rings for four or five frames; on a
  // steady path the filter is the better. The plan takes whichever erred
  // less last frame.
  struct Measured {
    int64_t t_ns = 0;
    double x_m = 0.0, y_m = 0.0, yaw_rad = 0.0;
  };
  std::array<Measured, 2> measured_{};  // the last two, newest last
  int measured_count_ = 0;              // consecutive measured frames held, 0-2
  MotionState extrapolated_;
  bool has_extrapolation_ = false;
  PredictionErrors extrapolation_errors_;
  void extrapolate(int64_t t_ns);
  void remember_measured(int64_t t_ns);
  // Map indices (j * codes + i) of the markers the last frame decoded:
  // decoded_last_[index] != 0, listed in last_decoded_.
  std::vector<uint8_t> decoded_last_;
  std::array<int32_t, kMaxMarkersPerFrame> last_decoded_{};
  int last_decoded_count_ = 0;
  void remember_decoded();
  int frames_since_full_ = 0;
  bool last_measured_ = false;  // the previous frame gave a measurement
  SweepCounts sweeps_;
  std::unique_ptr<FrameResult> result_;        // ~50 kB: on the heap, allocated once
  std::unique_ptr<FrameResult> check_result_;  // the scheduled check's, likewise
  bool defer_scheduled_ = false;
  bool check_due_ = false;
  Localization out_;
  bool had_fix_ = false;
  // Frames swept whole are found at half resolution first
  // (detector.halve_whole_sweeps, Pipeline::process_halved).
  bool halved_sweeps_ = false;
  // Whether the last frame decoded whole (centroids and edges) that
  // decided the tilt freed it. Edge points alone (a tracked or a halved
  // sweep's) free the tilt only after such a frame did: on edges along the
  // pixel grid they carry a bias that a tilt's keystone partly explains
  // (docs/decisions.md "A free tilt is confirmed by a whole decode").
  bool decode_freed_tilt_ = false;
  // The mount the tracking plan predicts with: the configured one, its
  // tilt as the last measurement's fit freed it (a camera tilted 23 mrad
  // past its calibration put every predicted marker 12 px and more off).
  CameraMount planned_mount_;
  void remember_fitted_tilt();
  RefusalHistogram refusals_;

  // The filter restarted, and the motion the tracking plan remembers
  // (prediction errors, the last measurements) forgotten with it.
  void forget_motion();
  // The filter's motion at this frame's time (predicted_) moved to the
  // optical centre, for a rolling shutter's readout; invalid when there is
  // no filter, no state within the prediction horizon or no readout.
  CameraMotion readout_motion() const;
  // Windows for this frame (plan_), or why to sweep it whole.
  FullSweepReason plan_sweep();
  // Sweeps the frame whole into *r: at half resolution first where that
  // suits, then at full resolution unless the halved sweep stood. Returns
  // whether it stood; adds the pixels swept to *swept_px.
  bool sweep_whole(const ImageView& image, const CameraMotion& motion, bool decode_whole,
                   FrameResult* r, int64_t* swept_px);
  // Whether a tracked sweep found what the plan expected.
  bool tracked_sweep_held() const;
  // The last sweep measured edge points alone and freed the tilt on them,
  // which no whole decode has confirmed.
  bool edges_alone_freed_tilt(const FrameResult& r) const;
  // After a whole decode: the tilt decision it made, if any.
  void remember_tilt_decision(const FrameResult& r);
  // The least-squares fit that gave r; null when r gave no pose or was
  // positioned another way. Only for the pipeline's last sweep.
  const LsqResult* last_fit(const FrameResult& r) const;
};

}  // namespace ceilpose
