#pragma once
// A command never writes over its own input (SPEC §10): an output path that
// names one of the files it reads, or a file inside a recording it reads, is
// refused before any work is done, and two outputs may not share a path.
#include <string>
#include <vector>

#include "core/result.h"

namespace ceilpose {

struct NamedPath {
  std::string option;  // as the user typed it: "--out", "--config"
  std::string path;    // empty: not given (skipped)
};

// Errors name both options and the path, e.g. "--out robot.yaml is --config's
// file: writing it would replace the input".
Result<void> check_outputs_are_not_inputs(const std::vector<NamedPath>& outputs,
                                          const std::vector<NamedPath>& input_files,
                                          const std::vector<NamedPath>& input_dirs = {});

}  // namespace ceilpose
