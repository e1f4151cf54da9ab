#pragma once
// The one path of a frame: pipeline (detection and positioning), temporal
// filter and fix state, for the daemon, `locate`/`evaluate`, the accuracy
// tests and the benchmarks alike. Counts every frame's refusal.
//
// Not thread-safe: one instance, called in frame order from one thread;
// refusals() may be read from any thread. localize() allocates nothing,
// throws nothing and logs nothing.
#include <memory>

#include "core/refusal.h"
#include "pipeline/localization.h"
#include "pipeline/pipeline.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/temporal_filter.h"

namespace ceilpose {

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

  // Between frames (SIGHUP): new tuning, mode and filter switch; the filter's
  // state is kept unless `reset_filter`.
  void reconfigure(const PipelineConfig& config, bool reset_filter);

  const PipelineConfig& config() const { return pipeline_.config(); }
  const RefusalHistogram& refusals() const { return refusals_; }
  const FilterStats& filter_stats() const { return filter_.stats(); }
  // The last frame's detection in detail (markers, rejects), for diagnostics.
  const FrameResult& last_frame() const { return *result_; }
  const Pipeline& pipeline() const { return pipeline_; }

 private:
  Pipeline pipeline_;
  TemporalFilter filter_;
  std::unique_ptr<FrameResult> result_;  // ~50 kB: on the heap, allocated once
  Localization out_;
  bool had_fix_ = false;
  RefusalHistogram refusals_;

  // The filter's motion predicted to t_ns and moved to the optical centre,
  // for a rolling shutter's readout; invalid when there is no filter, no
  // state within the prediction horizon or no readout.
  CameraMotion readout_motion(int64_t t_ns) const;
};

}  // namespace ceilpose
