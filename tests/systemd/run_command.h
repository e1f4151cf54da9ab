#pragma once
// Test support: runs a shell command, captures its output and exit status.
#include <string>

namespace ceilpose::test {

struct CommandResult {
  // Exit status; -1 when the shell could not start, had to be killed or died
  // of a signal.
  int status = -1;
  std::string output;  // stdout and stderr, interleaved
};

// Runs `command` through /bin/sh with stderr joined to stdout; kills it and
// fails the current test if it runs for 9 minutes.
CommandResult run_command(const std::string& command);
bool have_tool(const std::string& name);
// A fresh empty directory under the test temp dir.
std::string make_temp_dir(const std::string& stem);

}  // namespace ceilpose::test
