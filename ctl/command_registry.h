#pragma once
// Sub-commands of ceilposectl register themselves here from their own file:
//   static const CommandRegistrar kReg{"locate", &add_locate_command};
// The factory adds a CLI11 sub-command whose callback does the work and sets
// the process exit code through set_exit_code().
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace ceilpose::ctl {

// Documented exit codes of ceilposectl (see --help and README).
enum ExitCode : int {
  kExitOk = 0,
  kExitFailure = 1,   // runtime error (I/O, device, DDS)
  kExitUsage = 2,     // bad command line
  kExitNoDaemon = 3,  // no daemon publishing, or its pose is stale
  kExitBadInput = 4,  // malformed recording or configuration
  // A keystore that cannot be made or used: a missing file, a broken
  // signature, an expired certificate, a key that is not the certificate's.
  // The same number as ceilposed's.
  kExitKeystore = 6,
};

using CommandFactory = void (*)(CLI::App& app);

struct CommandRegistrar {
  CommandRegistrar(const char* name, CommandFactory factory);
};

struct RegisteredCommand {
  std::string name;
  CommandFactory factory;
};
std::vector<RegisteredCommand>& registered_commands();

void set_exit_code(int code);
int exit_code();

}  // namespace ceilpose::ctl
