// fleet_publisher: one simulated robot for the fleet harness
// (bench/fleet/run_fleet_harness). It publishes through the daemon's own DDS
// sink (pose, odometry, TF, the fleet's state) at --rate Hz from a circular
// trajectory with a full motion state, without any image work, so that 50
// of them fit on two cores. Prints "ready", then at the end one line:
//   published N cpu_s C rss_kb R failures F started_mono_ns S
// (S: when the process began, CLOCK_MONOTONIC, for the time it took to join).
#include <sys/resource.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <string>

#include "core/clock.h"
#include "daemon/dds_pose_sink.h"
#include "ipc/dds/dds_pose_publisher.h"
#include "keystore/keystore.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

long rss_kb() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ceilpose;
  const int64_t started_mono_ns = monotonic_ns();
  CLI::App app{"One simulated robot of the fleet harness: publishes through the DDS sink."};
  DdsOptions options;
  double rate_hz = 30.0;
  double duration_s = 30.0;
  double phase = 0.0;
  std::string keystore_dir;
  app.add_option("--robot", options.robot, "robot name")->required();
  app.add_option("--domain", options.domain.domain_id, "DDS domain id");
  app.add_option("--rate", rate_hz, "poses per second")->check(CLI::Range(0.1, 1000.0));
  app.add_option("--duration", duration_s, "seconds")->check(CLI::Range(0.1, 3600.0));
  app.add_option("--phase", phase, "start angle on the circle, radians");
  app.add_option("--keystore", keystore_dir, "DDS Security keystore; enclave = --robot");
  CLI11_PARSE(app, argc, argv);
  options.rviz.ceiling = false;  // the harness measures the pose path
  if (!keystore_dir.empty()) {
    auto files = keystore::check_enclave(keystore_dir, options.robot, std::time(nullptr));
    if (!files) {
      std::cerr << "fleet_publisher: " << files.error().message << "\n";
      return 6;
    }
    options.domain.security = std::move(files).value();
  }
  auto publisher = DdsPosePublisher::create(options);
  if (!publisher) {
    std::cerr << "fleet_publisher: " << publisher.error().message << "\n";
    return 1;
  }
  daemon::DdsPoseSink sink(&*publisher, 1000);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);
  std::printf("ready %s\n", options.robot.c_str());
  std::fflush(stdout);

  // A 1 m circle at 1.5 m/s around (2, 2), with the filter's state.
  constexpr double kRadius_m = 1.0, kSpeed_mps = 1.5;
  const double omega = kSpeed_mps / kRadius_m;
  const auto period_ns = static_cast<int64_t>(1e9 / rate_hz);
  const int64_t start_ns = monotonic_ns();
  const int64_t end_ns = start_ns + static_cast<int64_t>(duration_s * 1e9);
  uint64_t published = 0;
  for (int64_t next = start_ns; !g_stop && next < end_ns; next += period_ns) {
    const timespec at{static_cast<time_t>(next / 1'000'000'000),
                      static_cast<long>(next % 1'000'000'000)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr);
    const int64_t now = monotonic_ns();  // exposure = now: no image work here
    const double a = phase + omega * static_cast<double>(now - start_ns) * 1e-9;
    Localization loc;
    loc.frame.timestamp_ns = now;
    loc.published.valid = true;
    loc.published.pose = {2.0 + kRadius_m * std::cos(a), 2.0 + kRadius_m * std::sin(a),
                          a + M_PI / 2};
    loc.published.covariance = {1e-7, 0, 0, 0, 1e-7, 0, 0, 0, 1e-6};
    loc.published.mode = PositioningMode::kLeastSquares;
    loc.published.markers = 5;
    loc.measured = loc.published;
    loc.filtered = true;
    loc.motion.valid = true;
    loc.motion.time_ns = now;
    loc.motion.state.x = {loc.published.pose.x_m,
                          loc.published.pose.y_m,
                          loc.published.pose.yaw_rad,
                          -kSpeed_mps * std::sin(a),
                          kSpeed_mps * std::cos(a),
                          omega,
                          -kSpeed_mps * omega * std::cos(a),
                          -kSpeed_mps * omega * std::sin(a),
                          0.0};
    for (int i = 0; i < kMotionStates; ++i) loc.motion.state.p[i * kMotionStates + i] = 1e-6;
    loc.motion.jerk = {1.0, 1.0, 1.0};
    loc.motion.horizon_ms = 200.0;
    loc.fix = FixState::kOk;
    sink.consume(loc);
    ++published;
  }
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  const double cpu_s = static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
                       static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) * 1e-6;
  std::printf("published %llu cpu_s %.3f rss_kb %ld failures %llu started_mono_ns %lld\n",
              static_cast<unsigned long long>(published), cpu_s, rss_kb(),
              static_cast<unsigned long long>(sink.failures()),
              static_cast<long long>(started_mono_ns));
  std::fflush(stdout);
  publisher->dispose();
  return 0;
}
