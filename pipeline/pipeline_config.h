#pragma once
// Everything the pipeline needs to know about the world, the camera and its
// own tuning. Defaults are SPEC.md's; config/ceilpose.yaml mirrors them.
#include <memory>

#include "core/camera_model.h"
#include "core/ceiling_layout.h"
#include "core/ceiling_map.h"
#include "pipeline/detector_params.h"
#include "pipeline/positioning_params.h"

namespace ceilpose {

struct PipelineConfig {
  CameraIntrinsics intrinsics;
  CameraMount mount;
  CeilingLayout layout;
  // Where the markers really are (SPEC §8); null: the nominal grid of layout.
  std::shared_ptr<const CeilingMap> map;
  DetectorParams detector;
  PositioningParams positioning;
  FilterParams filter;
};

}  // namespace ceilpose
