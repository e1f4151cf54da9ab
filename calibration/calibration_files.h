#pragma once
// The files a lab's commissioning produces (SPEC §8, §9), named in the
// configuration (`camera.calibration_file`, `ceiling.map`) or on the command
// line (`--camera`, `--map`), loaded into what the pipeline reads. Every
// program that localizes (ceilposed, locate, evaluate, survey, render) loads
// them here, so they mean the same everywhere.
#include <string>

#include "core/result.h"
#include "pipeline/pipeline_config.h"

namespace ceilpose {

struct CalibrationFiles {
  std::string camera_file;  // SPEC §9 camera_info YAML; empty: the camera as configured
  std::string map_file;     // SPEC §8 ceiling map; empty: the nominal grid
};

// Replaces pipeline->intrinsics with the camera file's (whose image size
// must be the size pipeline->intrinsics already has: `capture` names where
// that size comes from, for the message) and sets pipeline->map from the map
// file, read for pipeline->layout. Nothing changes on error.
Result<void> load_calibration_files(const CalibrationFiles& files, const std::string& capture,
                                    PipelineConfig* pipeline);

}  // namespace ceilpose
