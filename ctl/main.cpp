// ceilposectl: query the daemon, record, render and localize offline.
#include <algorithm>
#include <iostream>

#include "ctl/command_registry.h"

int main(int argc, char** argv) {
  using namespace ceilpose::ctl;
  CLI::App app{
      "ceilposectl — query the ceilpose daemon, record, render and localize offline.\n"
      "Exit codes: 0 ok, 1 runtime error, 2 usage error, 3 no live daemon or stale pose,\n"
      "4 malformed recording or configuration."};
  app.require_subcommand(1);
  auto& commands = registered_commands();
  std::sort(commands.begin(), commands.end(),
            [](const RegisteredCommand& a, const RegisteredCommand& b) { return a.name < b.name; });
  for (const auto& c : commands) c.factory(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? kExitOk : kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "ceilposectl: " << e.what() << "\n";
    return kExitFailure;
  }
  return exit_code();
}
