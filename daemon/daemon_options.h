#pragma once
// ceilposed's command line (SPEC §7) and how it combines with the file.
#include <string>
#include <vector>

#include "config/service_config.h"
#include "core/result.h"

namespace ceilpose::daemon {

struct DaemonOptions {
  std::string config_path;                // empty: built-in defaults (SPEC)
  std::vector<ConfigOverride> overrides;  // --source, --robot, --shm, --domain, ...
  std::string check_config_path;          // --check-config FILE: validate and exit
  double duration_s = 0.0;                // --duration; 0 = until SIGTERM/SIGINT
  bool print_poses = false;               // --print-poses: a line per pose at <= 10 Hz
  bool print_config = false;              // --print-config: effective configuration, then exit
};

// Parses argv. On --help or a usage error, prints (help to stdout, errors to
// stderr) and returns the exit code to use in *exit_code; otherwise returns
// true and leaves *exit_code alone.
bool parse_command_line(int argc, char** argv, DaemonOptions* options, int* exit_code);

// The file (or defaults), then the command-line overrides.
Result<ServiceConfig> resolve_config(const DaemonOptions& options);

}  // namespace ceilpose::daemon
