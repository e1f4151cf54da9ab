// ceilposed: the ceiling-marker positioning service (SPEC §7, docs/service.md).
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
#include <system_error>

#include "core/exit_codes.h"
#include "core/resource_limits.h"
#include "daemon/cyclone_log.h"
#include "daemon/daemon_options.h"
#include "daemon/logging.h"
#include "daemon/service.h"
#include "daemon/signal_channel.h"
#include "daemon/thread_stacks.h"

namespace {

// Output lost (/dev/full, a closed pipe) is a failure, not a success.
int flushed(int exit_code) {
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    std::fprintf(stderr, "ceilposed: cannot write to stdout: %s\n", std::strerror(errno));
    return ceilpose::kExitFailure;
  }
  return exit_code;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ceilpose;
  using namespace ceilpose::daemon;
  // A reader that goes away (`ceilposed ... | head`) must give write errors,
  // which are handled, not a death that leaves the segment marked dead.
  std::signal(SIGPIPE, SIG_IGN);
  // Before anything else: a SIGTERM during start-up (loading the
  // configuration, the keystore, DDS discovery) waits for the service's
  // signal channel, which stops cleanly (signal_channel.h).
  hold_stop_signals();
  if (auto stacks = limit_thread_stacks(); !stacks) {
    std::fprintf(stderr, "ceilposed: %s\n", stacks.error().message.c_str());
    return kExitFailure;
  }
  DaemonOptions options;
  int exit_code = kExitOk;
  if (!parse_command_line(argc, argv, &options, &exit_code)) return exit_code;

  if (!options.check_config_path.empty()) {
    auto checked = load_config_file(options.check_config_path);
    if (checked) checked = with_calibration_files(std::move(checked).value());
    if (!checked) {
      std::fprintf(stderr, "ceilposed: %s\n", checked.error().message.c_str());
      return kExitBadConfig;
    }
    if (const std::string problem = keystore_problem(*checked); !problem.empty()) {
      std::fprintf(stderr, "ceilposed: DDS Security: %s\n", problem.c_str());
      return kExitKeystore;
    }
    std::printf("%s: valid\n", options.check_config_path.c_str());
    return flushed(kExitOk);
  }

  auto config = resolve_config(options);
  if (!config) {
    std::fprintf(stderr, "ceilposed: %s\n", config.error().message.c_str());
    return kExitBadConfig;
  }
  if (options.print_config) {
    std::fputs(dump_config(*config).c_str(), stdout);
    return flushed(kExitOk);
  }

  setup_logging(detect_log_target(), config->logging.level);
  route_cyclone_log();
  // Measured: with DDS on, 16 descriptors and 390 MiB of address space run;
  // 12 and 290 MiB crash inside Cyclone DDS. The needs leave a margin.
  if (const std::string limit = resource_limit_problem({32, 512}); !limit.empty()) {
    spdlog::critical("ceilposed: cannot start: {}", limit);
    return kExitFailure;
  }
  try {
    return run_service(*config, options);
  } catch (const std::bad_alloc&) {
    spdlog::critical(
        "ceilposed: out of memory (the address-space limit, ulimit -v / LimitAS=, or the "
        "machine's memory; ceilposed needs about 400 MB of address space, docs/service.md)");
    return kExitFailure;
  } catch (const std::system_error& e) {
    // std::thread reports a refused clone() as EAGAIN: "Resource temporarily unavailable".
    spdlog::critical(
        "ceilposed: cannot start: {} (thread stacks and buffers need about 400 MB of address "
        "space and a few threads: check ulimit -v / LimitAS= and ulimit -u / TasksMax=)",
        e.what());
    return kExitFailure;
  } catch (const std::exception& e) {
    spdlog::critical("ceilposed: {}", e.what());
    return kExitFailure;
  }
}
