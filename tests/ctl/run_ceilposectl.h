#pragma once
// Runs the built ceilposectl as a child process and collects what it said.
#include <string>
#include <vector>

namespace ceilpose::test {

struct CommandOutput {
  int exit_code = -1;  // -1 when the process did not exit normally
  std::string out;
  std::string err;
};

// Runs ceilposectl with `args` and captures its stdout and stderr. Kills it
// and fails the current test after `timeout_ms`. `scratch_dir` is unused
// (output comes back through pipes); it stays until the callers drop it.
CommandOutput run_ceilposectl(const std::vector<std::string>& args, const std::string& scratch_dir,
                              int timeout_ms = 60'000);

// True when this ceilposectl build has the sub-command.
bool has_subcommand(const std::string& name, const std::string& scratch_dir);

}  // namespace ceilpose::test
