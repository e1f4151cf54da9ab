#pragma once
// ceilposed's lifecycle, run by the control (main) thread:
//
//   start:  keystore check (DDS Security) -> capture thread (opens the
//           source) -> shared memory -> DDS -> pipeline thread -> READY=1
//   run:    one loop on the signal channel: SIGTERM/SIGINT stop, SIGHUP
//           reloads; between signals it feeds the watchdog while the pipeline
//           progresses, refreshes STATUS=, reports counted problems and
//           prints poses (--print-poses)
//   stop:   STOPPING=1 -> pipeline thread joined -> capture thread joined ->
//           shared memory marked stopped -> DDS disposed
//
// Everything a bad configuration could break is checked before anything
// starts, so a failed start leaves nothing half-made (no segment, no writers).
#include "config/service_config.h"
#include "daemon/daemon_options.h"

namespace ceilpose::daemon {

// Runs the service until stopped; returns the process exit code (exit_codes.h).
// `config` has been validated by resolve_config().
int run_service(const ServiceConfig& config, const DaemonOptions& options);

// With DDS on and dds.security.keystore set: "" when the enclave's files are
// what DDS Security accepts, else what is wrong, naming the file. Also ""
// without a keystore. The service checks the same before it starts anything;
// --check-config asks here.
std::string keystore_problem(const ServiceConfig& config);

}  // namespace ceilpose::daemon
