#include "ctl/command_registry.h"

#include <algorithm>

namespace ceilpose::ctl {

std::vector<RegisteredCommand>& registered_commands() {
  static std::vector<RegisteredCommand> commands;
  return commands;
}

CommandRegistrar::CommandRegistrar(const char* name, CommandFactory factory) {
  registered_commands().push_back({name, factory});
}

namespace {
int g_exit_code = kExitOk;
}

void set_exit_code(int code) { g_exit_code = code; }
int exit_code() { return g_exit_code; }

}  // namespace ceilpose::ctl
