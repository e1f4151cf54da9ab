// ceilposectl fleet: every robot seen on a DDS domain with its latest pose.
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "config/cli_checks.h"
#include "core/clock.h"
#include "core/json_text.h"
#include "ctl/command_registry.h"
#include "ctl/shm_option.h"
#include "ipc/dds/dds_fleet_listener.h"
#include "ipc/shm/shm_fleet_reader.h"
#include "keystore/keystore.h"

namespace ceilpose::ctl {
namespace {

struct FleetArgs {
  std::string shm;  // set: read the local daemon's fleet segment instead of DDS
  bool watch = false;
  int interval_ms = 200;
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

// ---- --shm: the local daemon's fleet segment (SPEC §12) ----

double speed_mps(const ceilpose_pose& p) {
  return (p.flags & CEILPOSE_POSE_MOTION) != 0 ? std::hypot(p.vx_mps, p.vy_mps) : NAN;
}

std::string fleet_json(const std::string& shm, const FleetInfo& info,
                       const std::vector<shm::FleetRecord>& robots, int64_t now_ns) {
  std::string out = "{\"shm\":" + json_quote(shm) +
                    ",\"capacity\":" + std::to_string(info.capacity) + ",\"robots\":[";
  for (size_t i = 0; i < robots.size(); ++i) {
    const shm::FleetRecord& r = robots[i];
    const Pose2D pose{r.pose.x_m, r.pose.y_m, r.pose.yaw_rad};
    out += (i > 0 ? ",{" : "{") + std::string("\"robot\":") + json_quote(r.robot) +
           pose_fields_json(&pose) + ",\"timestamp_ns\":" + std::to_string(r.pose.capture_mono_ns) +
           ",\"stamp_real_ns\":" + std::to_string(r.pose.capture_real_ns) +
           ",\"age_ms\":" + json_number((now_ns - r.pose.capture_mono_ns) * 1e-6) +
           ",\"latency_ms\":" + json_number(r.latency_ns * 1e-6) +
           ",\"speed_mps\":" + json_number(speed_mps(r.pose)) +
           ",\"stale\":" + ((r.fleet_flags & CEILPOSE_FLEET_STALE) != 0 ? "true" : "false") +
           ",\"samples\":" + std::to_string(r.samples) + ",\"lost\":" + std::to_string(r.lost) +
           "}";
  }
  out += "],\"accepted\":" + std::to_string(info.accepted) +
         ",\"refused\":{\"full\":" + std::to_string(info.refused_full) +
         ",\"future\":" + std::to_string(info.refused_future) +
         ",\"past\":" + std::to_string(info.refused_past) +
         ",\"invalid\":" + std::to_string(info.refused_invalid) +
         ",\"duplicate\":" + std::to_string(info.refused_duplicate) +
         "},\"removed\":" + std::to_string(info.removed) + "}";
  return out;
}

std::string fleet_table(const std::string& shm, const FleetInfo& info,
                        const std::vector<shm::FleetRecord>& robots, int64_t now_ns) {
  char line[256];
  std::snprintf(line, sizeof line, "%s: %u robots (of %u slots)\n", shm.c_str(), info.robots,
                info.capacity);
  std::string out = line;
  std::snprintf(line, sizeof line, "%-20s %10s %10s %9s %9s %8s %10s %5s\n", "ROBOT", "X_M", "Y_M",
                "YAW_DEG", "SPEED_MPS", "AGE_MS", "LATENCY_MS", "STALE");
  out += line;
  for (const shm::FleetRecord& r : robots) {
    std::snprintf(line, sizeof line, "%-20s %10.3f %10.3f %9.1f %9.2f %8.0f %10.1f %5s\n", r.robot,
                  r.pose.x_m, r.pose.y_m, r.pose.yaw_rad * 180.0 / M_PI, speed_mps(r.pose),
                  (now_ns - r.pose.capture_mono_ns) * 1e-6, r.latency_ns * 1e-6,
                  (r.fleet_flags & CEILPOSE_FLEET_STALE) != 0 ? "yes" : "no");
    out += line;
  }
  const uint64_t refused = info.refused_full + info.refused_future + info.refused_past +
                           info.refused_invalid + info.refused_duplicate;
  if (refused > 0) {
    std::snprintf(line, sizeof line,
                  "refused samples: %" PRIu64 " (no slot %" PRIu64 ", future %" PRIu64
                  ", past %" PRIu64 ", invalid %" PRIu64 ", duplicate name %" PRIu64 ")\n",
                  refused, info.refused_full, info.refused_future, info.refused_past,
                  info.refused_invalid, info.refused_duplicate);
    out += line;
  }
  return out;
}

int run_fleet_shm(const FleetArgs& args) {
  shm::ShmErrc code = shm::ShmErrc::kOk;
  auto reader = ShmFleetReader::open(args.shm, &code);
  if (!reader) {
    std::cerr << "ceilposectl fleet: " << reader.error().message << "\n";
    return code == shm::ShmErrc::kNotFound ? kExitNoDaemon : kExitFailure;
  }
  const bool tty = ::isatty(STDOUT_FILENO) != 0;
  std::vector<shm::FleetRecord> robots(reader->info().capacity);
  for (;;) {
    const uint32_t n = reader->read(0, robots.data(), static_cast<uint32_t>(robots.size()));
    const std::vector<shm::FleetRecord> shown(robots.begin(), robots.begin() + n);
    const FleetInfo info = reader->info();
    const int64_t now_ns = monotonic_ns();
    std::string text = args.json ? fleet_json(reader->name(), info, shown, now_ns) + "\n"
                                 : fleet_table(reader->name(), info, shown, now_ns);
    if (args.watch && tty && !args.json) text = "\033[H\033[2J" + text;  // redraw in place
    if (std::fputs(text.c_str(), stdout) < 0 || std::fflush(stdout) != 0) {
      std::cerr << "ceilposectl fleet: cannot write to stdout: " << std::strerror(errno) << "\n";
      return kExitFailure;
    }
    if (!args.watch) return kExitOk;
    std::this_thread::sleep_for(std::chrono::milliseconds(args.interval_ms));
  }
}

int run_fleet(const FleetArgs& args) {
  if (!args.shm.empty()) return run_fleet_shm(args);
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
      "With --shm NAME it reads instead the local ceilposed's fleet segment NAME-fleet (SPEC\n"
      "§12): every robot it keeps, with speed, age, latency (arrival - exposure) and stale;\n"
      "--watch redraws it every --interval-ms until interrupted.\n"
      "Honours CYCLONEDDS_URI; --interface/--peer replace it. With --keystore and --enclave\n"
      "it joins a secure fleet (DDS Security, SPEC §11) and sees only its robots.\n"
      "Exit 0 ok, 1 DDS or read failure, 2 usage, 3 no fleet segment (daemon not running), 6\n"
      "keystore refused (names the file).");
  auto* shm_option = add_shm_option(cmd, &args->shm);
  cmd->add_flag("--watch", args->watch, "with --shm: redraw until interrupted")->needs(shm_option);
  cmd->add_option("--interval-ms", args->interval_ms, "with --watch: period of the redraw, ms")
      ->default_val(200)
      ->check(CLI::Range(10, 60'000));
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
  // DDS listening and reading the segment are two modes: say so, not ignore.
  for (const char* dds_only : {"--duration", "--interface", "--peer", "--keystore"})
    shm_option->excludes(cmd->get_option(dds_only));
  cmd->callback([args] { set_exit_code(run_fleet(*args)); });
}

const CommandRegistrar kFleetRegistrar{"fleet", &add_fleet_command};

}  // namespace
}  // namespace ceilpose::ctl
