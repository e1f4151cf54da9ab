#include "tests/ctl/run_ceilposectl.h"

#include <gtest/gtest.h>

#include <map>

#include "tests/support/child_process.h"

namespace ceilpose::test {

CommandOutput run_ceilposectl(const std::vector<std::string>& args,
                              const std::string& /*scratch_dir*/, int timeout_ms) {
  std::vector<std::string> argv{CEILPOSECTL_PATH};
  argv.insert(argv.end(), args.begin(), args.end());
  ChildOptions options;
  options.capture_stderr = true;
  ChildProcess child(argv, options);
  if (!child.started()) {
    ADD_FAILURE() << child.start_error();
    return {};
  }
  CommandOutput result;
  if (const auto e = child.wait(timeout_ms)) {
    result.exit_code = e->code;
  } else {
    child.kill();
    ADD_FAILURE() << "ceilposectl did not finish within " << timeout_ms << " ms";
  }
  result.out = child.output();
  result.err = child.error_output();
  return result;
}

bool has_subcommand(const std::string& name, const std::string& scratch_dir) {
  // Asked once per name: every start of ceilposectl costs a few hundred ms.
  static std::map<std::string, bool> known;
  const auto it = known.find(name);
  if (it != known.end()) return it->second;
  const bool has = run_ceilposectl({name, "--help"}, scratch_dir).exit_code == 0;
  known[name] = has;
  return has;
}

}  // namespace ceilpose::test
