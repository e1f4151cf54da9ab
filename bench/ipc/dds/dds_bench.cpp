// DDS publish -> receive latency on loopback between two processes, beside
// Cyclone's own ddsperf ping/pong on the same configuration (the yardstick for our DDS path).
//
// A child `dds_bench --pong DOMAIN` echoes every pose it receives through its
// own DdsPosePublisher, from Cyclone's receive thread (a data-available
// listener), as `ddsperf pong` does.
//  - BM_DdsPoseRoundTrip: this process publishes through DdsPosePublisher and
//    sends the next ping from its listener as soon as the echo arrives, like
//    `ddsperf ping`; one iteration = kBatch round trips.
//  - BM_DdsPoseRoundTripWaitset: the same, but an application thread blocks
//    in a waitset for each echo (one iteration = one round trip), as a
//    consumer thread would: adds a thread wake-up per echo.
//  - BM_DdsPoseRoundTrip/secure:1 and the others with secure:1: the same
//    with DDS Security (issue 14): both processes authenticated with an
//    enclave of a keystore made here, topic data encrypted and signed.
//  - BM_DdsPose60Hz/secure:0|1: a robot's real load, one pose every 16.7 ms
//    for 10 s, each echoed back: round-trip percentiles, and this process's
//    CPU time (all its threads, Cyclone's included) per pose and as a share
//    of one core. Run together, the pair gives what security costs.
//  - BM_DdsperfRoundTrip: `ddsperf -D 5 ping` against `ddsperf pong` on the
//    same configuration, percentiles parsed from its output, and the ratios
//    of BM_DdsPoseRoundTrip's figures to it (target <= 1.5).
//
// ddsperf's ping prints half the round trip (it records (now - sent) / 2 as a
// one-way estimate), so its percentiles are doubled here before the ratio is
// taken. The benchmark checks that reading against ddsperf's own rate: one
// ping is in flight at a time, so round trips per second x mean round trip
// must come to about one second.
#include <benchmark/benchmark.h>
#include <dds/dds.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <mutex>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "core/clock.h"
#include "ipc/dds/dds_pose_publisher.h"
#include "keystore/keystore.h"
#include "tests/ipc/dds/dds_test_env.h"
#include "tests/support/child_process.h"

namespace ceilpose {
namespace {

constexpr int64_t kMatchTimeoutMs = 20'000;
constexpr int64_t kEchoTimeoutMs = 2'000;
constexpr size_t kBatch = 1000;  // round trips per iteration of the listener benchmark
// The domain is private to this run, so the names need not be.
constexpr char kPingRobot[] = "bench_ping";
constexpr char kPongRobot[] = "bench_pong";

// Round-trip percentiles of BM_DdsPoseRoundTrip, kept for the ratio printed
// by the ddsperf benchmark that runs after it.
double g_ours_p50_us = 0.0;
double g_ours_p99_us = 0.0;

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  std::nth_element(v.begin(), v.begin() + static_cast<ptrdiff_t>(k), v.end());
  return v[k];
}

struct WindowPercentiles {
  std::vector<double> p50_us, p99_us;
};

// Percentiles per one-second window of send times: the statistic ddsperf
// prints, so that the two can be compared like for like (the median over the
// windows damps a second in which another process held the CPU).
WindowPercentiles per_second_percentiles(const std::vector<int64_t>& sent_at_ns,
                                         const std::vector<double>& rtt_us) {
  WindowPercentiles out;
  size_t begin = 0;
  while (begin < rtt_us.size()) {
    size_t end = begin;
    while (end < rtt_us.size() && sent_at_ns[end] - sent_at_ns[begin] < 1'000'000'000) ++end;
    const std::vector<double> window(rtt_us.begin() + static_cast<ptrdiff_t>(begin),
                                     rtt_us.begin() + static_cast<ptrdiff_t>(end));
    if (window.size() >= 100) {  // skip a short tail window
      out.p50_us.push_back(percentile(window, 0.50));
      out.p99_us.push_back(percentile(window, 0.99));
    }
    begin = end;
  }
  return out;
}

// The temporary directory of the secure runs' keystore, once one is made;
// main removes it.
std::string g_keystore_root;

// The keystore of the secure runs, made once per run with an enclave for
// each side; empty if it could not be made.
const std::string& bench_keystore() {
  static const std::string dir = [] {
    char tmpl[] = "/tmp/ceilpose-dds-bench-XXXXXX";
    if (mkdtemp(tmpl) == nullptr) return std::string();
    g_keystore_root = tmpl;
    const std::string ks = g_keystore_root + "/keystore";
    const std::time_t now = std::time(nullptr);
    bool ok = keystore::init_keystore(ks, {now, 1}).ok();
    for (const char* robot : {kPingRobot, kPongRobot})
      ok = ok && keystore::add_enclave(ks, {.name = robot, .validity = {now, 1}}).ok();
    return ok ? ks : std::string();
  }();
  return dir;
}

// `keystore` empty: plain DDS; else DDS Security as enclave `robot` of it.
Result<DdsOptions> bench_options(const char* robot, uint32_t domain_id,
                                 const std::string& keystore) {
  DdsOptions o;
  o.robot = robot;
  o.domain.domain_id = domain_id;
  if (keystore.empty()) return o;
  auto files = keystore::check_enclave(keystore, robot, std::time(nullptr));
  if (!files) return files.error();
  o.domain.security = std::move(files).value();
  return o;
}

Result<DdsPosePublisher> bench_publisher(const char* robot, uint32_t domain_id,
                                         const std::string& keystore) {
  auto options = bench_options(robot, domain_id, keystore);
  if (!options) return options.error();
  return DdsPosePublisher::create(*options);
}

// A reliable reader of rt/<robot>/pose, with a data-available listener when
// `on_data` is given, else with a waitset to block on.
class PoseReader {
 public:
  PoseReader(dds_entity_t participant, const char* robot, dds_on_data_available_fn on_data,
             void* arg) {
    topic_ = dds_create_topic(participant, &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc,
                              pose_topic_name(robot).c_str(), nullptr, nullptr);
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 10);
    dds_listener_t* listener = nullptr;
    if (on_data != nullptr) {
      listener = dds_create_listener(arg);
      dds_lset_data_available(listener, on_data);
    }
    reader_ = dds_create_reader(participant, topic_, qos, listener);
    dds_delete_qos(qos);
    if (listener != nullptr) dds_delete_listener(listener);
    if (on_data != nullptr) return;  // the listener takes; nothing waits
    cond_ = dds_create_readcondition(reader_, DDS_ANY_STATE);
    waitset_ = dds_create_waitset(participant);
    dds_waitset_attach(waitset_, cond_, 0);
  }
  bool ok() const { return topic_ > 0 && reader_ > 0; }

  // Takes one sample without blocking.
  static bool take_now(dds_entity_t reader, geometry_msgs_msg_dds__PoseWithCovarianceStamped_* msg,
                       DdsPose* pose) {
    void* samples[1] = {msg};
    dds_sample_info_t info;
    if (dds_take(reader, samples, &info, 1, 1) != 1 || !info.valid_data) return false;
    *pose = from_message(*msg);
    return true;
  }

  // Blocks up to timeout_ms for the next sample.
  bool take(int64_t timeout_ms, DdsPose* pose) {
    const int64_t deadline_ns = monotonic_ns() + timeout_ms * 1'000'000;
    for (;;) {
      if (take_now(cond_, &msg_, pose)) return true;
      const int64_t left_ns = deadline_ns - monotonic_ns();
      if (left_ns <= 0) return false;
      dds_waitset_wait(waitset_, nullptr, 0, left_ns);
    }
  }

 private:
  dds_entity_t topic_ = 0, reader_ = 0, cond_ = 0, waitset_ = 0;
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg_{};
};

// --- pong process ----------------------------------------------------------

struct Pong {
  DdsPosePublisher* pub = nullptr;
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg{};
};

void pong_on_data(dds_entity_t reader, void* arg) {
  auto* pong = static_cast<Pong*>(arg);
  DdsPose pose;
  while (PoseReader::take_now(reader, &pong->msg, &pose)) (void)pong->pub->publish(pose);
}

int run_pong(uint32_t domain_id, const std::string& keystore) {
  auto pub = bench_publisher(kPongRobot, domain_id, keystore);
  if (!pub) {
    std::fprintf(stderr, "dds_bench --pong: %s\n", pub.error().message.c_str());
    return 1;
  }
  Pong pong;
  pong.pub = &*pub;
  PoseReader reader(pub->participant_handle(), kPingRobot, &pong_on_data, &pong);
  if (!reader.ok()) return 1;
  std::printf("ready\n");
  std::fflush(stdout);
  // Echoes happen on Cyclone's thread; live as long as the benchmark does.
  const pid_t parent = getppid();
  while (getppid() == parent) sleep(1);
  return 0;
}

// --- ping side ---------------------------------------------------------------

// The pong process and this side's publisher; readers are added to the
// publisher's participant, one participant per process as in ddsperf.
class PingSide {
 public:
  // secure: both sides authenticate and encrypt with bench_keystore().
  PingSide(uint32_t domain_id, bool secure)
      : secure_(secure),
        keystore_(secure ? bench_keystore() : std::string()),
        pong_({"/proc/self/exe", "--pong", std::to_string(domain_id), keystore_}),
        pub_(bench_publisher(kPingRobot, domain_id, keystore_)) {}

  // Null when ready, else what went wrong.
  const char* setup_error() {
    if (secure_ && keystore_.empty()) return "cannot make the benchmark's keystore";
    if (pong_.read_until("ready", kMatchTimeoutMs).find("ready") == std::string::npos) {
      return "pong process did not start";
    }
    if (!pub_.ok()) {
      error_ = "cannot create the DDS publisher: " + pub_.error().message;
      return error_.c_str();
    }
    return nullptr;
  }
  DdsPosePublisher& pub() { return *pub_; }
  dds_entity_t participant() const { return pub_->participant_handle(); }

 private:
  bool secure_;
  std::string keystore_;  // before pong_ and pub_, which use it
  test::ChildProcess pong_;
  Result<DdsPosePublisher> pub_;
  std::string error_;
};

// Round trips driven from the listener: each echo sends the next ping.
struct PingChain {
  DdsPosePublisher* pub = nullptr;
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg{};
  std::mutex m;
  std::condition_variable cv;
  DdsPose ping;
  int64_t sent_ns = 0;
  size_t target = 0;
  std::vector<double> rtt_us;
  std::vector<int64_t> sent_at_ns;  // per round trip, for per-second windows

  void send_next_locked() {
    ping.pose.x_m += 1.0;  // sequence number: echoes of older pings are ignored
    sent_ns = monotonic_ns();
    (void)pub->publish(ping);
  }

  // Runs n more round trips; false if the chain stalled (echo lost).
  bool run(size_t n, int64_t timeout_ms) {
    std::unique_lock lock(m);
    target = rtt_us.size() + n;
    send_next_locked();
    return cv.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                       [&] { return rtt_us.size() >= target; });
  }
};

void ping_on_data(dds_entity_t reader, void* arg) {
  auto* chain = static_cast<PingChain*>(arg);
  DdsPose echo;
  while (PoseReader::take_now(reader, &chain->msg, &echo)) {
    const int64_t now_ns = monotonic_ns();
    std::lock_guard lock(chain->m);
    if (echo.pose.x_m != chain->ping.pose.x_m || chain->rtt_us.size() >= chain->target) continue;
    chain->rtt_us.push_back(static_cast<double>(now_ns - chain->sent_ns) / 1e3);
    chain->sent_at_ns.push_back(chain->sent_ns);
    if (chain->rtt_us.size() < chain->target) {
      chain->send_next_locked();
    } else {
      chain->cv.notify_one();
    }
  }
}

void BM_DdsPoseRoundTrip(benchmark::State& state) {
  PingSide side(test::unique_domain_id(), state.range(0) != 0);
  if (const char* error = side.setup_error()) return state.SkipWithError(error);
  PingChain chain;
  chain.pub = &side.pub();
  chain.ping.valid = true;
  chain.rtt_us.reserve(1 << 22);
  chain.sent_at_ns.reserve(1 << 22);
  PoseReader reader(side.participant(), kPongRobot, &ping_on_data, &chain);
  // Discovery: a reliable writer drops what it writes before it has matched
  // the pong's reader, so ping until an echo comes back.
  const int64_t match_deadline_ns = monotonic_ns() + kMatchTimeoutMs * 1'000'000;
  bool matched = false;
  while (!matched && monotonic_ns() < match_deadline_ns) matched = chain.run(1, 50);
  if (!matched || !chain.run(kBatch, kEchoTimeoutMs)) {
    return state.SkipWithError("no echo from the pong process");
  }
  {
    std::lock_guard lock(chain.m);
    chain.rtt_us.clear();  // matching and warm-up
    chain.sent_at_ns.clear();
    chain.target = 0;
  }
  for (auto _ : state) {
    if (!chain.run(kBatch, kEchoTimeoutMs)) return state.SkipWithError("echo lost");
  }
  std::lock_guard lock(chain.m);
  const auto windows = per_second_percentiles(chain.sent_at_ns, chain.rtt_us);
  if (state.range(0) == 0) {  // ddsperf runs without security
    g_ours_p50_us = percentile(windows.p50_us, 0.5);
    g_ours_p99_us = percentile(windows.p99_us, 0.5);
  }
  state.counters["rtt_p50_us"] = percentile(chain.rtt_us, 0.50);
  state.counters["rtt_p99_us"] = percentile(chain.rtt_us, 0.99);
  state.counters["rtt_p50_us_1s_median"] = percentile(windows.p50_us, 0.5);
  state.counters["rtt_p99_us_1s_median"] = percentile(windows.p99_us, 0.5);
  state.counters["round_trips"] = static_cast<double>(chain.rtt_us.size());
  state.counters["payload_bytes"] = 364;
}
BENCHMARK(BM_DdsPoseRoundTrip)
    ->ArgName("secure")
    ->Arg(0)
    ->Arg(1)
    ->MinTime(5.0)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Pings until the pong's echo comes back (a reliable writer drops what it
// writes before it has matched), then drains the discovery echoes.
bool match_pong(DdsPosePublisher* pub, PoseReader* reader, DdsPose* ping) {
  DdsPose echo;
  const int64_t match_deadline_ns = monotonic_ns() + kMatchTimeoutMs * 1'000'000;
  bool matched = false;
  while (!matched && monotonic_ns() < match_deadline_ns) {
    (void)pub->publish(*ping);
    matched = reader->take(50, &echo);
  }
  while (matched && reader->take(100, &echo)) {
  }
  return matched;
}

// One ping, waited for in `reader`: the round trip in us, or < 0 when lost.
double round_trip_us(DdsPosePublisher* pub, PoseReader* reader, DdsPose* ping) {
  ping->pose.x_m += 1.0;
  const int64_t t0 = monotonic_ns();
  DdsPose echo;
  if (!pub->publish(*ping) || !reader->take(kEchoTimeoutMs, &echo) ||
      echo.pose.x_m != ping->pose.x_m) {
    return -1.0;
  }
  return static_cast<double>(monotonic_ns() - t0) / 1e3;
}

void BM_DdsPoseRoundTripWaitset(benchmark::State& state) {
  PingSide side(test::unique_domain_id(), state.range(0) != 0);
  if (const char* error = side.setup_error()) return state.SkipWithError(error);
  DdsPosePublisher* pub = &side.pub();
  PoseReader reader(side.participant(), kPongRobot, nullptr, nullptr);
  DdsPose ping;
  ping.valid = true;
  if (!match_pong(pub, &reader, &ping)) return state.SkipWithError("no echo from the pong process");

  std::vector<double> rtt_us;
  rtt_us.reserve(1 << 22);
  for (auto _ : state) {
    const double us = round_trip_us(pub, &reader, &ping);
    if (us < 0.0) return state.SkipWithError("echo lost or out of order");
    rtt_us.push_back(us);
  }
  state.counters["rtt_p50_us"] = percentile(rtt_us, 0.50);
  state.counters["rtt_p99_us"] = percentile(rtt_us, 0.99);
}
BENCHMARK(BM_DdsPoseRoundTripWaitset)
    ->ArgName("secure")
    ->Arg(0)
    ->Arg(1)
    ->MinTime(3.0)
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) / 1e6;
}

// A robot's load: 60 poses a second, each echoed, for 10 s per iteration.
void BM_DdsPose60Hz(benchmark::State& state) {
  constexpr int kRateHz = 60;
  constexpr int kPoses = 10 * kRateHz;
  PingSide side(test::unique_domain_id(), state.range(0) != 0);
  if (const char* error = side.setup_error()) return state.SkipWithError(error);
  DdsPosePublisher* pub = &side.pub();
  PoseReader reader(side.participant(), kPongRobot, nullptr, nullptr);
  DdsPose ping;
  ping.valid = true;
  if (!match_pong(pub, &reader, &ping)) return state.SkipWithError("no echo from the pong process");
  std::vector<double> rtt_us;
  double cpu_s = 0.0, wall_s = 0.0;
  for (auto _ : state) {
    const double cpu0 = process_cpu_s();
    const int64_t start_ns = monotonic_ns();
    for (int i = 0; i < kPoses; ++i) {
      const int64_t due_ns = start_ns + i * 1'000'000'000LL / kRateHz;
      const timespec until{static_cast<time_t>(due_ns / 1'000'000'000),
                           static_cast<long>(due_ns % 1'000'000'000)};
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr);
      const double us = round_trip_us(pub, &reader, &ping);
      if (us < 0.0) return state.SkipWithError("echo lost or out of order");
      rtt_us.push_back(us);
    }
    cpu_s += process_cpu_s() - cpu0;
    wall_s += static_cast<double>(monotonic_ns() - start_ns) / 1e9;
  }
  state.counters["rtt_p50_us"] = percentile(rtt_us, 0.50);
  state.counters["rtt_p99_us"] = percentile(rtt_us, 0.99);
  state.counters["cpu_us_per_pose"] = cpu_s * 1e6 / static_cast<double>(rtt_us.size());
  state.counters["cpu_percent_of_core"] = 100.0 * cpu_s / wall_s;
}
BENCHMARK(BM_DdsPose60Hz)
    ->ArgName("secure")
    ->Arg(0)
    ->Arg(1)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// ddsperf prints one line per second per peer:
//   [pid] 3.000  host:pid size 364 mean 28.9us min 10.8us 50% 28.2us ... cnt 17294
// where the times are half round trips and cnt counts the round trips of that
// second. The median of the per-second figures (first second excluded:
// discovery and warm-up) is reported, doubled to a round trip.
void BM_DdsperfRoundTrip(benchmark::State& state) {
  const std::string domain = std::to_string(test::unique_domain_id());
  std::vector<double> p50_us, p99_us, busy_fraction;
  for (auto _ : state) {
    test::ChildProcess pong({"/usr/bin/ddsperf", "-D", "8", "-i", domain, "pong"});
    // Same payload size as a serialized pose (364 bytes) for a fair figure.
    test::ChildProcess ping({"/usr/bin/ddsperf", "-D", "5", "-i", domain, "ping", "size", "364"});
    if (!pong.started() || !ping.started()) {
      return state.SkipWithError("cannot run /usr/bin/ddsperf (package cyclonedds-tools)");
    }
    ping.wait_exit(30'000);
    pong.terminate(5'000);
    const std::regex line(
        R"(^\[\d+\]\s+([\d.]+)\s+\S+ size \d+ mean ([\d.]+)us .* 50% ([\d.]+)us .* 99% ([\d.]+)us .* cnt (\d+))");
    std::istringstream in(ping.output());
    for (std::string l; std::getline(in, l);) {
      std::smatch m;
      if (std::regex_search(l, m, line) && std::stod(m[1]) > 1.5) {
        const double half_mean_us = std::stod(m[2]);
        const double round_trips = std::stod(m[5]);
        p50_us.push_back(2.0 * std::stod(m[3]));
        p99_us.push_back(2.0 * std::stod(m[4]));
        // Seconds spent in round trips per second of wall clock: about 1
        // when the printed times are half round trips, about 0.5 if they
        // were whole ones.
        busy_fraction.push_back(round_trips * 2.0 * half_mean_us / 1e6);
      }
    }
  }
  if (p50_us.empty()) return state.SkipWithError("no latency lines in ddsperf's output");
  const double ddsperf_p50 = percentile(p50_us, 0.5);
  const double ddsperf_p99 = percentile(p99_us, 0.5);
  const double busy = percentile(busy_fraction, 0.5);
  state.counters["rtt_p50_us"] = ddsperf_p50;
  state.counters["rtt_p99_us"] = ddsperf_p99;
  state.counters["round_trip_seconds_per_second"] = busy;
  if (busy < 0.75 || busy > 1.1) {
    return state.SkipWithError(
        "ddsperf's round trips per second x 2 x mean is not about 1 s: its output no longer "
        "prints half round trips, so the doubling here is wrong");
  }
  if (g_ours_p50_us > 0.0) {
    state.counters["ours_over_ddsperf_p50"] = g_ours_p50_us / ddsperf_p50;
    state.counters["ours_over_ddsperf_p99"] = g_ours_p99_us / ddsperf_p99;
    std::printf("DDS round trip, median of 1 s windows, 364-byte samples\n");
    std::printf(
        "ddsperf: round trips per second x 2 x printed mean = %.2f s per s "
        "(its printed times are half round trips)\n",
        busy);
    std::printf("DDS round trip p50: ours %.1f us, ddsperf %.1f us, ratio %.2f (target <= 1.5)\n",
                g_ours_p50_us, ddsperf_p50, g_ours_p50_us / ddsperf_p50);
    std::printf("DDS round trip p99: ours %.1f us, ddsperf %.1f us, ratio %.2f\n", g_ours_p99_us,
                ddsperf_p99, g_ours_p99_us / ddsperf_p99);
  }
}
BENCHMARK(BM_DdsperfRoundTrip)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace ceilpose

int main(int argc, char** argv) {
  // Loopback only, on a domain of this run, for us and for ddsperf alike.
  ceilpose::test::use_loopback_dds();
  if (argc > 3 && std::strcmp(argv[1], "--pong") == 0) {
    return ceilpose::run_pong(static_cast<uint32_t>(std::strtoul(argv[2], nullptr, 10)), argv[3]);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (!ceilpose::g_keystore_root.empty()) std::filesystem::remove_all(ceilpose::g_keystore_root);
  return 0;
}
