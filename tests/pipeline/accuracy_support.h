#pragma once
// Golden accuracy runs: render a simulator scenario frame by frame, localize
// each frame with the full pipeline, and score it with SPEC §6's metrics.
#include <cstdint>
#include <string>

#include "pipeline/accuracy_metrics.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/pose_estimate.h"
#include "pipeline/pose_sink.h"

namespace ceilpose::testing {

// Frames per set: modest in Release, fewer under sanitizers (3-10x slower);
// CEILPOSE_ACCURACY_FRAMES overrides (for the docs/accuracy.md table).
int accuracy_frames(int release_frames);

// Renders `frames` frames of scenario `name` (sim/scenarios.h) with `seed`
// and localizes them with `config` in `mode`, through the daemon's temporal
// filter when `filter`; `also` (if given) sees every frame too. The frames
// are rendered through a rolling shutter of rendered_readout_ms (the moving
// sets; config.intrinsics.readout_ms is what the localizer is told), handed
// over in `format` as a camera would (sim/camera_format.h) and, when
// `as_recorded`, converted to RGB24 as `ceilposectl record` stores it
// (capture::to_rgb24) before localizing: a replay of that camera. Fails the
// calling test (and returns an empty report) if the scenario cannot be made.
AccuracyReport run_scenario(const std::string& name, int frames, uint64_t seed,
                            PositioningMode mode, bool filter = false,
                            const PipelineConfig& config = PipelineConfig{},
                            PoseSink* also = nullptr, double rendered_readout_ms = 0.0,
                            PixelFormat format = PixelFormat::kRgb24, bool as_recorded = false);

}  // namespace ceilpose::testing
