#include "daemon/daemon_options.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "capture/source_spec.h"
#include "config/cli_checks.h"
#include "core/exit_codes.h"

namespace ceilpose::daemon {
namespace {

const CLI::Validator kNotEmpty = cli::not_empty();
const CLI::Validator kPositiveSeconds = cli::positive_seconds();

}  // namespace

bool parse_command_line(int argc, char** argv, DaemonOptions* options, int* exit_code) {
  CLI::App app{
      "ceilposed - localizes the robot from coded ceiling markers and publishes its pose\n"
      "on shared memory and DDS (ROS 2 PoseWithCovarianceStamped on rt/<robot>/pose).\n"
      "Command-line options override the configuration file; defaults are SPEC.md's.\n"
      "Signals: SIGTERM/SIGINT stop cleanly, SIGHUP reloads the configuration file.\n" +
      exit_codes_help(Program::kCeilposed)};
  app.set_version_flag("--version", "ceilposed 0.1.0");

  std::string source, robot, shm, log_level, keystore, enclave;
  int domain = -1;
  bool no_dds = false;
  // Not CLI::ExistingFile: a missing file is a configuration error (exit 3)
  // reported by the loader like any other.
  app.add_option("--config", options->config_path, "YAML configuration file (config/ceilpose.yaml)")
      ->check(kNotEmpty);
  app.add_option("--source", source, "frame source: " + std::string(capture::kSourceSpecForms))
      ->check(kNotEmpty);
  app.add_option("--robot", robot, "robot name, the DDS topic prefix (default: host name)")
      ->check(kNotEmpty);
  app.add_option("--shm", shm, "shared-memory segment name (default /ceilpose)")->check(kNotEmpty);
  app.add_option("--domain", domain, "DDS domain id (default 0)");
  app.add_flag("--no-dds", no_dds, "publish on shared memory only");
  app.add_option(
         "--keystore", keystore,
         "DDS Security keystore (ceilposectl keys): authenticate, encrypt and publish only\n"
         "as this robot's enclave (SPEC §11)")
      ->check(kNotEmpty);
  app.add_option("--enclave", enclave, "enclave of the keystore (default: the robot name)")
      ->check(kNotEmpty);
  app.add_option("--log-level", log_level, "trace | debug | info | warn | error | critical | off")
      ->check(kNotEmpty);
  app.add_option("--duration", options->duration_s,
                 "stop after SECONDS, a number above 0 (default: run until stopped)")
      ->check(kPositiveSeconds);
  app.add_flag("--print-poses", options->print_poses,
               "print a line per pose (at most 10 per second): time, x, y, yaw, mode, markers,\n"
               "ground truth and error when the source knows it, latency");
  app.add_option("--check-config", options->check_config_path,
                 "validate FILE (and the keystore it names) and exit: 0 when valid, 3 with the\n"
                 "problem on stderr, 6 when DDS Security would refuse its keystore")
      ->check(kNotEmpty);
  app.add_flag("--print-config", options->print_config,
               "print the effective configuration (file + options) as YAML and exit");

  cli::refuse_non_finite_numbers(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    *exit_code = rc == 0 ? kExitOk : kExitUsage;
    return false;
  }
  if (!source.empty()) options->overrides.push_back({"capture.source", source, "--source"});
  if (!robot.empty()) options->overrides.push_back({"dds.robot_name", robot, "--robot"});
  if (!shm.empty()) options->overrides.push_back({"ipc.shm_name", shm, "--shm"});
  if (domain >= 0 || app.count("--domain") > 0)
    options->overrides.push_back({"dds.domain_id", std::to_string(domain), "--domain"});
  if (!keystore.empty())
    options->overrides.push_back({"dds.security.keystore", keystore, "--keystore"});
  if (!enclave.empty())
    options->overrides.push_back({"dds.security.enclave", enclave, "--enclave"});
  if (no_dds) options->overrides.push_back({"dds.enabled", "false", "--no-dds"});
  if (!log_level.empty()) options->overrides.push_back({"logging.level", log_level, "--log-level"});
  return true;
}

Result<ServiceConfig> resolve_config(const DaemonOptions& options) {
  ServiceConfig base = default_config();
  if (!options.config_path.empty()) {
    auto loaded = load_config_file(options.config_path);
    if (!loaded) return loaded.error();
    base = std::move(loaded).value();
  }
  auto configured = apply_overrides(base, options.overrides);
  if (!configured) return configured;
  return with_calibration_files(std::move(configured).value());
}

}  // namespace ceilpose::daemon
