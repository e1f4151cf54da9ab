#pragma once
// The observations of `survey` and `calibrate robot`: every frame of one or
// more recordings localized in order, each frame with a pose of its own kept
// with its whole decoded markers (their image points).
#include <string>
#include <vector>

#include "calibration/calibration_files.h"
#include "core/camera_model.h"
#include "pipeline/pipeline_config.h"
#include "survey/bundle_adjustment.h"

namespace ceilpose::ctl {

struct FrameSources {
  std::vector<std::string> dirs;  // --replay, in order
  std::string config_file;        // --config
  CalibrationFiles calibration;   // --camera, --map
  // A survey starts from the nominal grid (no map) and the configured mount;
  // `calibrate robot` localizes against the map with the camera at the
  // robot's origin (offset and mounting yaw zero: what it measures).
  bool use_map = false;
  bool zero_mount = false;
};

// Decodes every frame with `camera` (null: each recording's own, or
// --camera's). Returns the exit code (errors printed, prefixed by
// `command`); *config is the first recording's pipeline configuration.
// Recordings of different cameras are refused.
int collect_survey_frames(const FrameSources& sources, const char* command,
                          const CameraIntrinsics* camera, PipelineConfig* config,
                          std::vector<SurveyFrame>* frames);

}  // namespace ceilpose::ctl
