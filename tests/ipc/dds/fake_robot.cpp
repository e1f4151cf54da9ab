// ceilpose_dds_fake_robot: publishes one robot's pose on DDS at a fixed rate,
// as a stand-in daemon for tests and demos. Prints "ready" once its writers
// exist, then publishes until --duration elapses or SIGTERM/SIGINT.
#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <vector>

#include "core/clock.h"
#include "ipc/dds/dds_pose_publisher.h"
#include "keystore/keystore.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

}  // namespace

int main(int argc, char** argv) {
  using namespace ceilpose;
  CLI::App app{"Publish a fake robot's pose on DDS (rt/<robot>/pose) for tests and demos."};
  DdsOptions options;
  double x_m = 0.0, y_m = 0.0, yaw_rad = 0.0, rate_hz = 50.0, duration_s = 30.0;
  std::vector<double> velocity;
  int64_t stamp_ns = -1;
  bool best_effort = false;
  std::string keystore_dir, enclave;
  app.add_option("--robot", options.robot, "robot name (ROS name)")->required();
  app.add_option("--domain", options.domain.domain_id, "DDS domain id")->default_val(0);
  app.add_option("--x", x_m, "x, metres");
  app.add_option("--y", y_m, "y, metres");
  app.add_option("--yaw", yaw_rad, "yaw, radians");
  app.add_option("--velocity", velocity,
                 "world-frame vx_mps vy_mps yaw_rate_radps (default: no velocity)")
      ->expected(3);
  app.add_option("--rate", rate_hz, "poses per second")->check(CLI::Range(0.1, 10000.0));
  app.add_option("--duration", duration_s, "stop after this many seconds")
      ->check(CLI::Range(0.0, 3600.0));
  app.add_option("--stamp-ns", stamp_ns,
                 "fixed header stamp (CLOCK_REALTIME ns) instead of the current time");
  app.add_flag("--best-effort", best_effort, "best-effort writer instead of reliable");
  app.add_option("--interface", options.domain.interfaces, "network interface (repeatable)");
  app.add_option("--peer", options.domain.peers, "unicast discovery peer (repeatable)");
  app.add_option("--keystore", keystore_dir, "DDS Security keystore (ceilposectl keys)");
  app.add_option("--enclave", enclave, "enclave of --keystore (default: --robot)");
  CLI11_PARSE(app, argc, argv);
  if (!keystore_dir.empty()) {
    auto files = keystore::check_enclave(keystore_dir, enclave.empty() ? options.robot : enclave,
                                         std::time(nullptr));
    if (!files) {
      std::cerr << "ceilpose_dds_fake_robot: " << files.error().message << "\n";
      return 6;
    }
    options.domain.security = std::move(files).value();
  }
  if (best_effort) options.reliability = DdsReliability::kBestEffort;

  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);
  auto publisher = DdsPosePublisher::create(options);
  if (!publisher) {
    std::cerr << "ceilpose_dds_fake_robot: " << publisher.error().message << "\n";
    return 1;
  }
  // The nominal ceiling of the default layout, for RViz (rt/<robot>/ceiling).
  const CeilingLayout layout;
  if (auto ok = publisher->publish_ceiling(layout, CeilingMap(layout)); !ok) {
    std::cerr << "ceilpose_dds_fake_robot: " << ok.error().message << "\n";
    return 1;
  }
  std::printf("ready %s\n", publisher->pose_topic().c_str());
  std::fflush(stdout);

  DdsPose pose;
  pose.valid = true;
  pose.pose = {x_m, y_m, yaw_rad};
  pose.covariance = {1e-4, 1e-5, 0.0, 1e-5, 2e-4, 0.0, 0.0, 0.0, 3e-3};
  if (velocity.size() == 3) {
    pose.has_velocity = true;
    pose.velocity = {velocity[0], velocity[1], velocity[2]};
    pose.velocity_covariance = {4e-4, 0.0, 0.0, 0.0, 1e-4, 0.0, 0.0, 0.0, 9e-4};
  }
  DdsStatus status;
  status.fix = true;
  status.fps = static_cast<float>(rate_hz);
  const auto period_ns = static_cast<int64_t>(1e9 / rate_hz);
  const int64_t end_ns = monotonic_ns() + static_cast<int64_t>(duration_s * 1e9);
  int64_t next_ns = monotonic_ns();
  while (g_stop == 0 && monotonic_ns() < end_ns) {
    pose.capture_realtime_ns = stamp_ns >= 0 ? stamp_ns : realtime_ns();
    if (auto ok = publisher->publish(pose); !ok) {
      std::cerr << "ceilpose_dds_fake_robot: " << ok.error().message << "\n";
      return 1;
    }
    status.publish_realtime_ns = realtime_ns();
    ++status.frames;
    if (auto ok = publisher->publish_status(status); !ok) {
      std::cerr << "ceilpose_dds_fake_robot: " << ok.error().message << "\n";
      return 1;
    }
    next_ns += period_ns;
    const timespec until{static_cast<time_t>(next_ns / 1'000'000'000),
                         static_cast<long>(next_ns % 1'000'000'000)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr);
  }
  return 0;
}
