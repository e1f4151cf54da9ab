// fleet_probe: watches an observer's fleet segment for the harness. Polls
// every --poll-us; for each new sample of each robot records the keeper's
// receive time minus the exposure (both this host's CLOCK_MONOTONIC: the
// harness runs every robot on one host, so the clocks agree), and notes when
// all --robots robots were first present. At the end prints one line:
//   robots R present_ms T samples S lost L p50_ms a p99_ms b max_ms c refused F
// and then, for each robot, when it was first present (CLOCK_MONOTONIC):
//   first_present ROBOT NS
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/clock.h"
#include "ipc/shm/shm_fleet_reader.h"

int main(int argc, char** argv) {
  using namespace ceilpose;
  std::string shm;
  uint32_t want = 0;
  double duration_s = 10.0, settle_s = 0.0;
  long poll_us = 500;
  for (int k = 1; k + 1 < argc; k += 2) {
    const std::string a = argv[k];
    if (a == "--shm")
      shm = argv[k + 1];
    else if (a == "--robots")
      want = static_cast<uint32_t>(std::atoi(argv[k + 1]));
    else if (a == "--duration")
      duration_s = std::atof(argv[k + 1]);
    else if (a == "--settle")
      settle_s = std::atof(argv[k + 1]);
    else if (a == "--poll-us")
      poll_us = std::atol(argv[k + 1]);
  }
  if (shm.empty() || want == 0) {
    std::fprintf(stderr,
                 "usage: %s --shm NAME --robots N [--duration S] [--settle S] [--poll-us U]\n",
                 argv[0]);
    return 2;
  }
  const int64_t start_ns = monotonic_ns();
  // The observer may still be starting: retry opening for 10 s.
  std::optional<ShmFleetReader> reader;
  while (!reader && monotonic_ns() - start_ns < 10'000'000'000) {
    auto r = ShmFleetReader::open(shm);
    if (r)
      reader.emplace(std::move(r).value());
    else
      usleep(20'000);
  }
  if (!reader) {
    std::fprintf(stderr, "fleet_probe: no fleet segment for %s\n", shm.c_str());
    return 1;
  }
  const uint32_t capacity = reader->info().capacity;
  std::vector<shm::FleetRecord> out(capacity);
  std::map<std::string, uint64_t> last_samples;
  std::map<std::string, int64_t> first_present_ns;
  std::vector<double> latency_ms;
  latency_ms.reserve(1'000'000);
  int64_t present_ns = -1;
  const int64_t measure_from = start_ns + static_cast<int64_t>(settle_s * 1e9);
  const int64_t end_ns = start_ns + static_cast<int64_t>(duration_s * 1e9);
  uint64_t samples = 0;
  for (int64_t now = monotonic_ns(); now < end_ns; now = monotonic_ns()) {
    const uint32_t n = reader->read(0, out.data(), capacity);
    if (present_ns < 0 && n >= want) present_ns = now - start_ns;
    for (uint32_t i = 0; i < n; ++i) {
      first_present_ns.emplace(out[i].robot, now);
      uint64_t& seen = last_samples[out[i].robot];
      if (out[i].samples == seen) continue;
      seen = out[i].samples;
      if (now < measure_from) continue;
      ++samples;
      latency_ms.push_back(
          static_cast<double>(out[i].received_mono_ns - out[i].pose.capture_mono_ns) * 1e-6);
    }
    timespec pause{0, poll_us * 1000};
    nanosleep(&pause, nullptr);
  }
  uint64_t lost = 0;
  const uint32_t n = reader->read(0, out.data(), capacity);
  for (uint32_t i = 0; i < n; ++i) lost += out[i].lost;
  std::sort(latency_ms.begin(), latency_ms.end());
  auto pct = [&](double q) {
    return latency_ms.empty() ? NAN : latency_ms[static_cast<size_t>(q * (latency_ms.size() - 1))];
  };
  const FleetInfo info = reader->info();
  std::printf(
      "robots %u present_ms %.0f samples_seen %llu accepted %llu lost %llu p50_ms %.3f p99_ms %.3f "
      "max_ms %.3f refused %llu\n",
      n, present_ns < 0 ? NAN : present_ns * 1e-6, static_cast<unsigned long long>(samples),
      static_cast<unsigned long long>(info.accepted), static_cast<unsigned long long>(lost),
      pct(0.5), pct(0.99), latency_ms.empty() ? NAN : latency_ms.back(),
      static_cast<unsigned long long>(info.refused_full + info.refused_future + info.refused_past +
                                      info.refused_invalid + info.refused_duplicate));
  for (const auto& [robot, ns] : first_present_ns)
    std::printf("first_present %s %lld\n", robot.c_str(), static_cast<long long>(ns));
  return 0;
}
