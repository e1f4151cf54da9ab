#pragma once
// Exit codes of ceilposed (documented in --help and docs/service.md). systemd's
// Restart=on-failure restarts on any of the non-zero ones; the unit's
// RestartPreventExitStatus stops it retrying a configuration that cannot work.
namespace ceilpose::daemon {

enum ExitCode : int {
  kExitOk = 0,             // stopped by SIGTERM/SIGINT, --duration elapsed, or the replay ended
  kExitRuntime = 1,        // failure while running (pipeline thread, shared memory, DDS)
  kExitUsage = 2,          // bad command line
  kExitBadConfig = 3,      // configuration file missing, malformed or out of range
  kExitSourceFailure = 4,  // the frame source could not be opened or failed for good
  // The shared-memory name is held: another live ceilposed, or another
  // user's file, link or directory in /dev/shm. Retrying cannot help.
  kExitShmNameTaken = 5,
  // DDS Security refused: the keystore misses a file, a signature does not
  // verify, a certificate has expired or is not the CA's, or the key is not
  // the certificate's. Nothing was published; retrying cannot help.
  kExitKeystore = 6,
};

}  // namespace ceilpose::daemon
