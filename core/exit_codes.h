#pragma once
// The exit codes of ceilposed and ceilposectl: one table, from which both
// programs' --help, the systemd unit's RestartPreventExitStatus (checked by
// tests/systemd/unit_file_test.cpp) and docs/service.md's table are made.
// SPEC §10 fixes 0, 1, 2 and 4 for the tools; a number keeps the meaning
// scripts and the unit already rely on in each program, so 3 and 4 are read
// per program (see docs/decisions.md, "One table of exit codes").
#include <span>
#include <string>

namespace ceilpose {

enum ExitCode : int {
  kExitOk = 0,
  kExitFailure = 1,  // could not be done (I/O, device, DDS, a fit), saying why
  kExitUsage = 2,    // bad command line
  // ceilposed: the configuration file is missing, malformed or out of range.
  kExitBadConfig = 3,
  // ceilposectl: no daemon publishing, or its pose is stale.
  kExitNoDaemon = 3,
  // ceilposed: the frame source could not be opened or failed for good.
  kExitSourceFailure = 4,
  // ceilposectl: a malformed recording, map, camera or configuration file.
  kExitBadInput = 4,
  // ceilposed: the shared-memory name is held (another live ceilposed, or
  // another user's file, link or directory in /dev/shm).
  kExitShmNameTaken = 5,
  // Both: DDS Security refused a keystore (a missing file, a broken
  // signature, an expired or foreign certificate, a key that is not the
  // certificate's), naming the file.
  kExitKeystore = 6,
};

enum class Program { kCeilposed, kCeilposectl };

struct ExitCodeRow {
  int code;
  const char* ceilposed;    // meaning in ceilposed; nullptr: never returned
  const char* ceilposectl;  // meaning in ceilposectl; nullptr: never returned
  // systemd must not restart ceilposed after it: retrying cannot help.
  bool restart_cannot_help;
};

std::span<const ExitCodeRow> exit_code_table();

// "Exit codes: 0 ok, 1 ..., 6 ..." for a program's --help.
std::string exit_codes_help(Program program);

// The unit's RestartPreventExitStatus value, e.g. "3 5 6".
std::string restart_prevent_exit_status();

}  // namespace ceilpose
