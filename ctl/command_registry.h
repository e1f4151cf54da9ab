#pragma once
// Sub-commands of ceilposectl register themselves here from their own file:
//   const CommandRegistrar kLocateRegistrar{"locate", &add_locate_command};
// Each registrar has its own name: ceilposectl compiles its files in batches
// (unity build), where one anonymous namespace holds several files.
// The factory adds a CLI11 sub-command whose callback does the work and sets
// the process exit code through set_exit_code().
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

#include "core/exit_codes.h"

namespace ceilpose::ctl {

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
