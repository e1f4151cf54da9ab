#include "tests/systemd/run_command.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "tests/support/child_process.h"

namespace ceilpose::test {
namespace {

// Under packaging_tests' ctest TIMEOUT (600 s), so a hung command fails the
// test with its name rather than being killed by ctest without one.
constexpr int kCommandTimeoutMs = 540'000;

}  // namespace

CommandResult run_command(const std::string& command) {
  const RunOutput r = run_to_end({"/bin/sh", "-c", command + " 2>&1"}, kCommandTimeoutMs);
  if (!r.failure.empty()) ADD_FAILURE() << "`" << command << "`: " << r.failure;
  // r.err holds only what the shell itself said (a syntax error, say).
  return {r.exit_code, r.out + r.err};
}

bool have_tool(const std::string& name) {
  return run_command("command -v " + name + " >/dev/null").status == 0;
}

std::string make_temp_dir(const std::string& stem) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) /
                                    ("ceilpose-" + stem + "-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace ceilpose::test
