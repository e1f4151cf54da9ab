// ceilposectl: query the daemon, record, render and localize offline.
#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <new>

#include "config/cli_checks.h"
#include "ctl/command_registry.h"

namespace {

// What a command printed must have reached stdout: /dev/full, a full disk or
// a reader that went away (SIGPIPE is ignored, so that shows as EPIPE here)
// is a failure, never a success with the output lost.
int with_output_checked(int rc) {
  std::cout.flush();
  if (std::fflush(stdout) == 0 && !std::ferror(stdout) && std::cout.good()) return rc;
  std::fprintf(stderr, "ceilposectl: cannot write to stdout: %s\n", std::strerror(errno));
  return rc == ceilpose::kExitOk ? ceilpose::kExitFailure : rc;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ceilpose;
  using namespace ceilpose::ctl;
  std::signal(SIGPIPE, SIG_IGN);
  CLI::App app{"ceilposectl — query the ceilpose daemon, record, render and localize offline.\n" +
               exit_codes_help(Program::kCeilposectl)};
  app.require_subcommand(1);
  auto& commands = registered_commands();
  std::sort(commands.begin(), commands.end(),
            [](const RegisteredCommand& a, const RegisteredCommand& b) { return a.name < b.name; });
  for (const auto& c : commands) c.factory(app);
  cli::refuse_non_finite_numbers(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? kExitOk : kExitUsage;
  } catch (const std::bad_alloc&) {
    std::cerr << "ceilposectl: out of memory: the address-space limit (ulimit -v) or the "
                 "machine's memory is too small for this work\n";
    return kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << "ceilposectl: " << e.what() << "\n";
    return kExitFailure;
  }
  return with_output_checked(exit_code());
}
