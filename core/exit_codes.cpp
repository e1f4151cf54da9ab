#include "core/exit_codes.h"

namespace ceilpose {
namespace {

constexpr ExitCodeRow kTable[] = {
    {kExitOk, "ok (stopped by SIGTERM/SIGINT, --duration elapsed or the replay ended)", "ok",
     false},
    {kExitFailure, "runtime failure (pipeline thread, shared memory, DDS, resource limits)",
     "could not be done (I/O, device, DDS, a fit the data cannot support), saying why", false},
    {kExitUsage, "usage error", "usage error", false},
    {kExitBadConfig, "bad configuration", "no live daemon, or its pose is stale", true},
    {kExitSourceFailure, "frame source failure",
     "malformed input (recording, map, camera or configuration file)", false},
    {kExitShmNameTaken,
     "shared-memory name held (another ceilposed, or another user's file in /dev/shm)", nullptr,
     true},
    {kExitKeystore, "keystore refused (DDS Security; names the file)",
     "keystore refused (DDS Security; names the file)", true},
};

}  // namespace

std::span<const ExitCodeRow> exit_code_table() { return kTable; }

std::string exit_codes_help(Program program) {
  std::string text = "Exit codes:";
  for (const ExitCodeRow& row : kTable) {
    const char* meaning = program == Program::kCeilposed ? row.ceilposed : row.ceilposectl;
    if (meaning == nullptr) continue;
    text += (row.code == 0 ? " " : ", ") + std::to_string(row.code) + " " + meaning;
  }
  return text + ".";
}

std::string restart_prevent_exit_status() {
  std::string codes;
  for (const ExitCodeRow& row : kTable) {
    if (!row.restart_cannot_help) continue;
    if (!codes.empty()) codes += ' ';
    codes += std::to_string(row.code);
  }
  return codes;
}

}  // namespace ceilpose
