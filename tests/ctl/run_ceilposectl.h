#pragma once
// Runs the built ceilposectl as a child process and collects what it said.
#include <string>
#include <vector>

#include "tests/support/child_process.h"

namespace ceilpose::test {

using CommandOutput = RunOutput;

// Runs ceilposectl with `args` and captures its stdout and stderr. Kills it
// and fails the current test after `timeout_ms`.
// `stdout_fd` >= 0: its stdout is that descriptor instead (see ChildOptions).
CommandOutput run_ceilposectl(const std::vector<std::string>& args, int timeout_ms = 60'000,
                              int stdout_fd = -1);

}  // namespace ceilpose::test
