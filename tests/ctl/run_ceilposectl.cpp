#include "tests/ctl/run_ceilposectl.h"

#include <gtest/gtest.h>

#include <map>

namespace ceilpose::test {

CommandOutput run_ceilposectl(const std::vector<std::string>& args, int timeout_ms, int stdout_fd) {
  std::vector<std::string> argv{CEILPOSECTL_PATH};
  argv.insert(argv.end(), args.begin(), args.end());
  CommandOutput result = run_to_end(argv, timeout_ms, stdout_fd);
  if (!result.failure.empty()) ADD_FAILURE() << result.failure;
  return result;
}

bool has_subcommand(const std::string& name) {
  // Asked once per name: every start of ceilposectl costs a few hundred ms.
  static std::map<std::string, bool> known;
  const auto it = known.find(name);
  if (it != known.end()) return it->second;
  const bool has = run_ceilposectl({name, "--help"}).exit_code == 0;
  known[name] = has;
  return has;
}

}  // namespace ceilpose::test
