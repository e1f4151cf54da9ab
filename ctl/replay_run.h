#pragma once
// `locate` and `evaluate`: the configuration (SPEC defaults, --config, the
// recording's camera), then every frame of the recording in order through
// the Localizer to the command's sinks (JSON Lines, accuracy).
#include <optional>
#include <span>
#include <string>

#include "calibration/calibration_files.h"
#include "ctl/command_registry.h"
#include "pipeline/localizer.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/pose_sink.h"
#include "recording/frame_prefetcher.h"
#include "recording/recording_reader.h"

namespace ceilpose::ctl {

struct ReplayArgs {
  std::string dir;
  std::string config_file;
  CalibrationFiles calibration;  // --camera, --map: over the configuration's
  std::string mode_text;         // empty: the configuration's mode (SPEC default auto)
  bool filter = false;
  // --predict-ms (implies --filter): how far past each frame's time the pose
  // is predicted; unset without the option.
  std::optional<double> predict_ms;
  int decode_threads = FramePrefetcher::default_threads();
};

// Adds --replay, --config, --camera, --map, --filter, --predict-ms, --mode and
// --decode-threads.
void add_replay_options(CLI::App* cmd, ReplayArgs* args);

struct ReplaySetup {
  PipelineConfig config;
  std::optional<RecordingReader> reader;
};

// Loads the configuration and opens the recording; the camera is the
// recording's unless a calibration file (--camera, else camera.calibration_file)
// replaces it, and the map is --map's, else ceiling.map's. On failure prints
// the error (naming file and line) and returns the exit code, else kExitOk.
int prepare_replay(const ReplayArgs& args, const char* command, ReplaySetup* setup);

// Localizes every frame in order, as fast as possible, handing each
// Localization to every sink. Returns kExitOk, or kExitBadInput (message
// printed) when a frame cannot be loaded. Warns once when frames were refused
// because the markers contradict the configured heights.
int run_replay(const ReplayArgs& args, const char* command, const ReplaySetup& setup,
               std::span<PoseSink* const> sinks);

}  // namespace ceilpose::ctl
