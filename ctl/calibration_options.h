#pragma once
// --camera FILE and --map FILE, the same on every command that localizes or
// renders (SPEC §5, §7): they override camera.calibration_file and
// ceiling.map of --config.
#include <CLI/CLI.hpp>
#include <string>

#include "calibration/calibration_files.h"

namespace ceilpose::ctl {

inline void add_camera_option(CLI::App* cmd, std::string* camera_file) {
  cmd->add_option("--camera", *camera_file,
                  "Camera calibration, ROS camera_info YAML (SPEC §9, `calibrate camera`); "
                  "replaces the recording's camera and camera.calibration_file");
}

inline void add_map_option(CLI::App* cmd, std::string* map_file) {
  cmd->add_option("--map", *map_file,
                  "Surveyed ceiling map (SPEC §8, `survey`) instead of the nominal grid; "
                  "overrides ceiling.map");
}

inline void add_calibration_options(CLI::App* cmd, CalibrationFiles* files) {
  add_camera_option(cmd, &files->camera_file);
  add_map_option(cmd, &files->map_file);
}

// calibrate mount and calibrate robot: how far from the turning centre a
// camera may sit (calibration/mount_estimate.h).
inline void add_max_offset_option(CLI::App* cmd, double* max_offset_m) {
  cmd->add_option("--max-offset-m", *max_offset_m,
                  "Farthest the camera may sit from the robot's turning centre, m: a wider "
                  "turning circle is an arc (turning while driving), not a turn in place")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 2.0));
}

}  // namespace ceilpose::ctl
