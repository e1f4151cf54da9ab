#pragma once
// The pipeline's configuration for a camera and mount of the independent
// renderer, so that the pipeline is told what the renderer drew.
#include "pipeline/pipeline_config.h"
#include "tests/pipeline/independent_renderer_support.h"

namespace ceilpose::testing::xcheck {

PipelineConfig config_for(const XCamera& camera, const XMount& mount = {});

}  // namespace ceilpose::testing::xcheck
