// ceilposectl fleet: every robot seen on a DDS domain with its latest pose.
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "config/cli_checks.h"
#include "core/clock.h"
#include "core/json_text.h"
#include "ctl/command_registry.h"
#include "ipc/dds/dds_fleet_listener.h"
#include "keystore/keystore.h"

namespace ceilpose::ctl {
namespace {

struct FleetArgs {
  uint32_t domain_id = 0;
  bool json = false;
  double duration_s = 2.0;
  std::vector<std::string> interfaces;
  std::vector<std::string> peers;
  std::string keystore_dir;  // set: listen as enclave `enclave` of this keystore
  std::string enclave;
};

std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  return buf;
}

int64_t age_ms(const FleetRobot& r, int64_t now_ns) {
  return (now_ns - r.received_monotonic_ns) / 1'000'000;
}

void print_json(const FleetArgs& args, const std::vector<FleetRobot>& robots, int64_t now_ns) {
  std::string out = "{\"domain\":" + std::to_string(args.domain_id) +
                    ",\"duration_s\":" + json_number(args.duration_s) + ",\"robots\":[";
  bool first = true;
  for (const auto& r : robots) {
    if (!first) out += ",";
    first = false;
    out += "{\"robot\":" + json_quote(r.robot) + ",\"topic\":" + json_quote(r.topic) +
           ",\"type\":" + json_quote(r.type_name) +
           ",\"encoding\":" + (r.xcdr1 ? "\"XCDR1\"" : "\"XCDR2\"") +
           ",\"samples\":" + std::to_string(r.samples);
    if (r.samples > 0) {
      out += pose_fields_json(&r.latest.pose) +
             ",\"stamp_ns\":" + std::to_string(r.latest.capture_realtime_ns) +
             ",\"age_ms\":" + std::to_string(age_ms(r, now_ns));
    } else {
      out += pose_fields_json(nullptr) + R"(,"stamp_ns":null,"age_ms":null)";
    }
    out += "}";
  }
  out += "]}";
  std::cout << out << std::endl;
}

void print_table(const FleetArgs& args, const std::vector<FleetRobot>& robots, int64_t now_ns) {
  if (robots.empty()) {
    std::printf("no robots seen on domain %u in %.1f s\n", args.domain_id, args.duration_s);
    return;
  }
  std::printf("%-20s %10s %10s %9s %9s %8s\n", "ROBOT", "X_M", "Y_M", "YAW_DEG", "AGE_MS",
              "SAMPLES");
  for (const auto& r : robots) {
    if (r.samples == 0) {
      std::printf("%-20s %10s %10s %9s %9s %8d\n", r.robot.c_str(), "-", "-", "-", "-", 0);
      continue;
    }
    std::printf("%-20s %10.3f %10.3f %9.1f %9" PRId64 " %8" PRIu64 "\n", r.robot.c_str(),
                r.latest.pose.x_m, r.latest.pose.y_m, r.latest.pose.yaw_rad * 180.0 / M_PI,
                age_ms(r, now_ns), r.samples);
  }
}

int run_fleet(const FleetArgs& args) {
  DdsDomainOptions options;
  options.domain_id = args.domain_id;
  options.interfaces = args.interfaces;
  options.peers = args.peers;
  if (!args.keystore_dir.empty()) {
    auto files = keystore::check_enclave(args.keystore_dir, args.enclave, std::time(nullptr));
    if (!files) {
      std::cerr << "ceilposectl fleet: keystore: " << files.error().message << "\n";
      return kExitKeystore;
    }
    options.security = std::move(files).value();
  }
  auto listener = DdsFleetListener::create(options);
  if (!listener) {
    std::cerr << "ceilposectl fleet: " << listener.error().message << "\n";
    return kExitFailure;
  }
  const auto duration_ms = static_cast<int64_t>(std::llround(args.duration_s * 1000.0));
  if (auto ok = listener->listen_for(duration_ms); !ok) {
    std::cerr << "ceilposectl fleet: " << ok.error().message << "\n";
    return kExitFailure;
  }
  const int64_t now_ns = monotonic_ns();
  const auto robots = listener->robots();
  if (args.json) {
    print_json(args, robots, now_ns);
  } else {
    print_table(args, robots, now_ns);
  }
  return kExitOk;
}

void add_fleet_command(CLI::App& app) {
  auto args = std::make_shared<FleetArgs>();
  CLI::App* cmd = app.add_subcommand(
      "fleet",
      "List every robot publishing poses on a DDS domain (topics rt/<robot>/pose of type "
      "geometry_msgs/msg/PoseWithCovarianceStamped) with its latest pose and its age.\n"
      "Listens for --duration seconds; exits 0 even when no robot is seen.\n"
      "Honours CYCLONEDDS_URI; --interface/--peer replace it. With --keystore and --enclave\n"
      "it joins a secure fleet (DDS Security, SPEC §11) and sees only its robots.\n"
      "Exit 0 ok, 1 DDS failure, 2 usage, 6 keystore refused (names the file).");
  cmd->add_option("--domain", args->domain_id, "DDS domain id")
      ->default_val(0)
      ->check(CLI::Range(0, 230));
  cmd->add_flag("--json", args->json, "one JSON object for scripts instead of a table");
  cmd->add_option("--duration", args->duration_s, "how long to listen, seconds")
      ->default_val(2.0)
      ->check(cli::positive_seconds())
      ->check(CLI::Range(0.1, 3600.0));
  cmd->add_option("--interface", args->interfaces,
                  "network interface to use (repeatable), e.g. eth0 or lo");
  cmd->add_option("--peer", args->peers,
                  "unicast discovery peer address (repeatable), e.g. 127.0.0.1");
  auto* keystore = cmd->add_option("--keystore", args->keystore_dir,
                                   "keystore directory (ceilposectl keys): listen securely")
                       ->check(cli::not_empty());
  cmd->add_option("--enclave", args->enclave, "enclave of the keystore to listen as")
      ->check(cli::not_empty())
      ->needs(keystore);
  keystore->needs(cmd->get_option("--enclave"));
  cmd->callback([args] { set_exit_code(run_fleet(*args)); });
}

const CommandRegistrar kReg{"fleet", &add_fleet_command};

}  // namespace
}  // namespace ceilpose::ctl
