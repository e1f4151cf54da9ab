#pragma once
// Test support: runs a shell command, captures its output and exit status.
#include <string>

namespace ceilpose::test {

struct CommandResult {
  int status = -1;     // exit status; -1 when the command could not run
  std::string output;  // stdout and stderr, interleaved
};

CommandResult run_command(const std::string& command);
bool have_tool(const std::string& name);
// A fresh empty directory under the test temp dir.
std::string make_temp_dir(const std::string& stem);

}  // namespace ceilpose::test
