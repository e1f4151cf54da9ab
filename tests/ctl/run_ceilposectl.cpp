#include "tests/ctl/run_ceilposectl.h"

#include <gtest/gtest.h>

namespace ceilpose::test {

CommandOutput run_ceilposectl(const std::vector<std::string>& args, int timeout_ms, int stdout_fd) {
  std::vector<std::string> argv{CEILPOSECTL_PATH};
  argv.insert(argv.end(), args.begin(), args.end());
  CommandOutput result = run_to_end(argv, timeout_ms, stdout_fd);
  if (!result.failure.empty()) ADD_FAILURE() << result.failure;
  return result;
}

}  // namespace ceilpose::test
