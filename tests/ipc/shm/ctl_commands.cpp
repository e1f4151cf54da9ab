// ceilposectl status / pose / watch run as separate processes against a
// writer in the test process (SPEC §7 names, flags, JSON fields, exit codes).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <thread>
#include <vector>

#include "core/clock.h"
#include "core/exit_codes.h"
#include "core/refusal.h"
#include "ipc/shm/shm_layout.h"
#include "ipc/shm/shm_pose_reader.h"
#include "ipc/shm/shm_pose_writer.h"
#include "shm_test_support.h"
#include "tests/support/child_process.h"

namespace ceilpose {
namespace {

constexpr int kRunTimeoutMs = 30'000;
// ceilposectl can take seconds to start on a loaded machine; tests that
// expect a live pose must not find it stale because of that.
const char* const kLenientStaleMs = "60000";

// ceilposectl's command line with `args`.
std::vector<std::string> ctl(const std::vector<std::string>& args) {
  std::vector<std::string> argv{CEILPOSECTL_PATH};
  argv.insert(argv.end(), args.begin(), args.end());
  return argv;
}

test::ChildOptions capturing_stderr() {
  test::ChildOptions options;
  options.capture_stderr = true;
  return options;
}

class CtlCommands : public test::ShmFixture {
 protected:
  int run(const std::vector<std::string>& args) {
    test::RunOutput r = test::run_to_end(ctl(args), kRunTimeoutMs);
    out_ = std::move(r.out);
    err_ = std::move(r.err);
    return r.exit_code;
  }
  std::string out_;
  std::string err_;
};

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

PoseRecord sample_pose(int64_t capture_mono_ns) {
  PoseRecord p{};
  p.capture_mono_ns = capture_mono_ns;
  p.x_m = 1.25;
  p.y_m = -0.5;
  p.yaw_rad = 0.3;
  p.covariance[0] = 1e-6;
  p.flags = kPoseValid | kPoseFiltered;
  p.mode = CEILPOSE_MODE_LSQ;
  p.markers = 9;
  return p;
}

size_t count_lines(const std::string& text) {
  return static_cast<size_t>(std::count(text.begin(), text.end(), '\n'));
}

TEST_F(CtlCommands, PoseJsonPrintsLivePoseWithSpecFieldsAndExitsZero) {
  ASSERT_NO_FATAL_FAILURE(start());
  writer().publish(sample_pose(123456789));
  EXPECT_EQ(run({"pose", "--shm", name(), "--json", "--stale-ms", kLenientStaleMs}), 0) << err_;
  EXPECT_TRUE(contains(out_, "\"seq\":1,")) << out_;
  EXPECT_TRUE(contains(out_, "\"valid\":true")) << out_;
  EXPECT_TRUE(contains(out_, "\"x_m\":1.2500000")) << out_;
  EXPECT_TRUE(contains(out_, "\"y_m\":-0.5000000")) << out_;
  EXPECT_TRUE(contains(out_, "\"yaw_rad\":0.3000000")) << out_;
  EXPECT_TRUE(contains(out_, "\"mode\":\"lsq\"")) << out_;
  EXPECT_TRUE(contains(out_, "\"markers\":9")) << out_;
  EXPECT_TRUE(contains(out_, "\"timestamp_ns\":123456789")) << out_;
  EXPECT_EQ(count_lines(out_), 1u);
}

// The number after "key": in `text` (NaN when absent).
double number_after(const std::string& text, const std::string& key) {
  const size_t at = text.find("\"" + key + "\":");
  return at == std::string::npos ? NAN : std::strtod(text.c_str() + at + key.size() + 3, nullptr);
}

// Driving East at 1 m/s; the horizon (in ms) the daemon would publish.
PoseRecord moving_pose(int64_t capture_mono_ns, double horizon_ms) {
  PoseRecord p = sample_pose(capture_mono_ns);
  MotionEstimate m;
  m.valid = true;
  m.time_ns = capture_mono_ns;
  m.state.x = {p.x_m, p.y_m, p.yaw_rad, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  for (int i = 0; i < kMotionStates; ++i) m.state.p[i * kMotionStates + i] = 1e-6;
  m.jerk = {1.0, 1.0, 1.0};
  m.horizon_ms = horizon_ms;
  set_pose_motion(&p, m);
  return p;
}

TEST_F(CtlCommands, PoseJsonCarriesTheFiltersVelocity) {
  ASSERT_NO_FATAL_FAILURE(start());
  writer().publish(moving_pose(123456789, 200.0));
  EXPECT_EQ(run({"pose", "--shm", name(), "--json", "--stale-ms", kLenientStaleMs}), 0) << err_;
  EXPECT_EQ(number_after(out_, "vx_mps"), 1.0) << out_;
  EXPECT_EQ(number_after(out_, "vy_mps"), 0.0) << out_;
  EXPECT_EQ(number_after(out_, "yaw_rate_radps"), 0.0) << out_;
  EXPECT_TRUE(contains(out_, "\"velocity_cov\":[1.000e-06,")) << out_;
  EXPECT_FALSE(contains(out_, "predict_ms")) << out_;
}

TEST_F(CtlCommands, PoseAtPredictsWhereTheRobotIsNowOrSoon) {
  ASSERT_NO_FATAL_FAILURE(start());
  // A horizon lenient enough for ceilposectl's start-up on a loaded machine.
  writer().publish(moving_pose(monotonic_ns(), 60000.0));
  EXPECT_EQ(run({"pose", "--shm", name(), "--json", "--at", "now", "--stale-ms", kLenientStaleMs}),
            0)
      << err_;
  double ahead_ms = number_after(out_, "predict_ms");
  EXPECT_GT(ahead_ms, 0.0) << out_;
  EXPECT_NEAR(number_after(out_, "x_m"), 1.25 + ahead_ms * 1e-3, 1e-6) << out_;
  EXPECT_EQ(run({"pose", "--shm", name(), "--json", "--at", "+250", "--stale-ms", kLenientStaleMs}),
            0)
      << err_;
  ahead_ms = number_after(out_, "predict_ms");
  EXPECT_GT(ahead_ms, 250.0) << out_;
  EXPECT_NEAR(number_after(out_, "x_m"), 1.25 + ahead_ms * 1e-3, 1e-6) << out_;
  EXPECT_EQ(run({"pose", "--shm", name(), "--at", "soon"}), 2);
  EXPECT_EQ(run({"pose", "--shm", name(), "--at", "+-5"}), 2);
}

TEST_F(CtlCommands, PoseAtRefusesBeyondTheHorizonOrWithoutMotion) {
  ASSERT_NO_FATAL_FAILURE(start());
  writer().publish(moving_pose(monotonic_ns(), 200.0));
  EXPECT_EQ(run({"pose", "--shm", name(), "--at", "+5000", "--stale-ms", kLenientStaleMs}), 1);
  EXPECT_TRUE(contains(err_, "beyond the daemon's predict horizon of 200 ms")) << err_;
  writer().publish(sample_pose(monotonic_ns()));  // no motion
  EXPECT_EQ(run({"pose", "--shm", name(), "--at", "now", "--stale-ms", kLenientStaleMs}), 1);
  EXPECT_TRUE(contains(err_, "nothing to predict from")) << err_;
}

TEST_F(CtlCommands, PoseJsonHasNullPoseFieldsWhenInvalid) {
  ASSERT_NO_FATAL_FAILURE(start());
  PoseRecord p = sample_pose(1);
  p.flags = 0;
  writer().publish(p);
  EXPECT_EQ(run({"pose", "--shm", name(), "--json", "--stale-ms", kLenientStaleMs}), 0) << err_;
  EXPECT_TRUE(contains(out_, "\"valid\":false,\"x_m\":null,\"y_m\":null,\"yaw_rad\":null")) << out_;
}

TEST_F(CtlCommands, PoseHumanOutputShowsPositionAndMode) {
  ASSERT_NO_FATAL_FAILURE(start());
  writer().publish(sample_pose(1));
  EXPECT_EQ(run({"pose", "--shm", name(), "--stale-ms", kLenientStaleMs}), 0) << err_;
  EXPECT_TRUE(contains(out_, "x 1.2500 m")) << out_;
  EXPECT_TRUE(contains(out_, "mode lsq")) << out_;
}

TEST_F(CtlCommands, PoseExitsNoDaemonWhenSegmentIsMissing) {
  EXPECT_EQ(run({"pose", "--shm", name()}), kExitNoDaemon);
  EXPECT_TRUE(contains(err_, "no daemon")) << err_;
  EXPECT_TRUE(contains(err_, name())) << err_;
}

TEST_F(CtlCommands, PoseExitsNoDaemonWhenPoseIsStale) {
  ASSERT_NO_FATAL_FAILURE(start());
  PoseRecord p = sample_pose(1);
  p.publish_mono_ns = monotonic_ns() - 5'000'000'000;  // published 5 s ago
  writer().publish(p);
  EXPECT_EQ(run({"pose", "--shm", name(), "--stale-ms", "1000"}), kExitNoDaemon);
  EXPECT_TRUE(contains(err_, "stale")) << err_;
}

TEST_F(CtlCommands, PoseExitsNoDaemonWhenDaemonStopped) {
  ASSERT_NO_FATAL_FAILURE(start());
  writer().publish(sample_pose(1));
  writer().mark_stopped();
  EXPECT_EQ(run({"pose", "--shm", name(), "--json"}), kExitNoDaemon);
  EXPECT_TRUE(contains(err_, "stopped")) << err_;
  EXPECT_TRUE(contains(out_, "\"live\":false")) << out_;
}

TEST_F(CtlCommands, PoseExitsNoDaemonBeforeFirstPose) {
  ASSERT_NO_FATAL_FAILURE(start());
  EXPECT_EQ(run({"pose", "--shm", name()}), kExitNoDaemon);
  EXPECT_TRUE(contains(err_, "no pose yet")) << err_;
}

TEST_F(CtlCommands, StatusJsonShowsDaemonHealth) {
  ASSERT_NO_FATAL_FAILURE(start());
  StatusRecord s{};
  s.fps = 29.5;
  s.frames = 1000;
  s.drops = 2;
  s.skipped = 3;
  s.outages = 1;
  s.latency_p50_us = 4100;
  s.latency_p90_us = 5200;
  s.latency_p99_us = 7300;
  s.latency_max_us = 9900;
  s.fix_state = CEILPOSE_FIX_OK;
  s.refusal_count = kRefusalCount;
  s.refusals[static_cast<int>(Refusal::kNone)] = 990;
  s.refusals[static_cast<int>(Refusal::kNoMarkers)] = 7;
  s.refusals[static_cast<int>(Refusal::kWrongHeights)] = 3;
  set_status_source(&s, "v4l2:/dev/video0");
  writer().update_status(s);
  writer().publish(sample_pose(1));
  EXPECT_EQ(run({"status", "--shm", name(), "--json", "--stale-ms", kLenientStaleMs}), 0) << err_;
  for (const std::string field :
       {"\"state\":\"running\"", "\"liveness\":\"live\"", "\"fps\":29.50", "\"frames\":1000",
        "\"drops\":2", "\"skipped\":3", "\"outages\":1", "\"p50\":4100", "\"p90\":5200",
        "\"p99\":7300", "\"max\":9900", "\"fix\":\"fix\"", "\"source\":\"v4l2:/dev/video0\"",
        "\"last_seq\":1", "\"refusals\":{\"unusable_frame\":0,", "\"no_markers\":7,",
        "\"wrong_heights\":3,", "\"localized\":990"}) {
    EXPECT_TRUE(contains(out_, field)) << field << " missing in " << out_;
  }
  EXPECT_TRUE(contains(out_, "\"pid\":" + std::to_string(::getpid()))) << out_;
}

TEST_F(CtlCommands, StatusHumanOutputNamesSourceLatencyAndRefusals) {
  ASSERT_NO_FATAL_FAILURE(start());
  StatusRecord s{};
  s.latency_p99_us = 7300;
  s.refusal_count = kRefusalCount;
  s.refusals[static_cast<int>(Refusal::kUnreadableMarkers)] = 12;
  set_status_source(&s, "synthetic");
  writer().update_status(s);
  EXPECT_EQ(run({"status", "--shm", name(), "--stale-ms", kLenientStaleMs}), 0) << err_;
  EXPECT_TRUE(contains(out_, "synthetic")) << out_;
  EXPECT_TRUE(contains(out_, "p99 7.30 ms")) << out_;
  EXPECT_TRUE(contains(out_, "no pose    unreadable_markers 12  (frames per refusal")) << out_;
}

TEST_F(CtlCommands, PoseJudgesStalenessByTheDaemonsPublishedLimit) {
  // The writer says 200 ms (ipc.stale_after_ms); a pose 2 s old is stale
  // without --stale-ms, and the message names the daemon's limit.
  ASSERT_NO_FATAL_FAILURE(start(50, 200));
  EXPECT_EQ(reader().writer_info().stale_after_ms, 200);
  PoseRecord p = sample_pose(1);
  p.publish_mono_ns = monotonic_ns() - 2'000'000'000;
  writer().publish(p);
  EXPECT_EQ(run({"pose", "--shm", name()}), kExitNoDaemon);
  EXPECT_TRUE(contains(err_, "limit 200 ms")) << err_;
}

TEST_F(CtlCommands, PoseTakesALenientDaemonLimitToo) {
  ASSERT_NO_FATAL_FAILURE(start(50, 600'000));
  PoseRecord p = sample_pose(1);
  p.publish_mono_ns = monotonic_ns() - 2'000'000'000;
  writer().publish(p);
  EXPECT_EQ(run({"pose", "--shm", name()}), 0) << err_;
}

TEST_F(CtlCommands, StatusSaysStoppedAndExitsNoDaemonAfterCleanStop) {
  ASSERT_NO_FATAL_FAILURE(start());
  writer().publish(sample_pose(1));
  writer().mark_stopped();
  EXPECT_EQ(run({"status", "--shm", name()}), kExitNoDaemon);
  EXPECT_TRUE(contains(out_, "stopped")) << out_;
  EXPECT_TRUE(contains(err_, "stopped")) << err_;
}

TEST_F(CtlCommands, StatusExitsNoDaemonWhenSegmentIsMissing) {
  EXPECT_EQ(run({"status", "--shm", name()}), kExitNoDaemon);
  EXPECT_TRUE(contains(err_, name())) << err_;
}

TEST_F(CtlCommands, WatchJsonStreamsCountPosesAsTheyArePublished) {
  ASSERT_NO_FATAL_FAILURE(start());
  std::atomic<bool> finished{false};
  std::thread publisher([&] {
    for (int64_t k = 1; !finished.load() && k < 10'000; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      writer().publish(sample_pose(k));
    }
  });
  const int rc = run({"watch", "--shm", name(), "--json", "--count", "3"});
  finished.store(true);
  publisher.join();
  EXPECT_EQ(rc, 0) << err_;
  EXPECT_EQ(count_lines(out_), 3u) << out_;
  EXPECT_TRUE(contains(out_, "\"markers\":9")) << out_;
}

// Issue 15: pose, status and watch into /dev/full used to exit 0 with their
// output lost.
TEST_F(CtlCommands, PoseStatusAndWatchIntoAFullDeviceFailSayingSo) {
  ASSERT_NO_FATAL_FAILURE(start());
  std::atomic<bool> finished{false};
  std::thread publisher([&] {
    for (int64_t k = 1; !finished.load() && k < 10'000; ++k) {
      writer().publish(sample_pose(k));
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"pose", "--shm", name(), "--stale-ms", kLenientStaleMs},
        {"pose", "--shm", name(), "--json", "--stale-ms", kLenientStaleMs},
        {"status", "--shm", name(), "--stale-ms", kLenientStaleMs},
        {"status", "--shm", name(), "--json", "--stale-ms", kLenientStaleMs},
        {"watch", "--shm", name(), "--count", "3"},
        {"watch", "--shm", name(), "--json", "--count", "3"}}) {
    const int full = ::open("/dev/full", O_WRONLY | O_CLOEXEC);
    ASSERT_GE(full, 0);
    const test::RunOutput r = test::run_to_end(ctl(args), kRunTimeoutMs, full);
    ::close(full);
    EXPECT_EQ(r.exit_code, 1) << args[0] << ": " << r.err;
    EXPECT_TRUE(contains(r.err, "cannot write to stdout: No space left on device"))
        << args[0] << ": " << r.err;
  }
  finished.store(true);
  publisher.join();
}

TEST_F(CtlCommands, WatchWaitsForDaemonThatStartsLater) {
  test::ChildProcess watch(ctl({"watch", "--shm", name(), "--json", "--count", "2"}),
                           capturing_stderr());
  ASSERT_TRUE(watch.started()) << watch.start_error();
  ASSERT_TRUE(contains(watch.read_error_until("waiting for ceilposed", kRunTimeoutMs),
                       "waiting for ceilposed"))
      << watch.error_output();
  ASSERT_NO_FATAL_FAILURE(start());
  writer().publish(sample_pose(1));
  ASSERT_TRUE(contains(watch.read_until("\"seq\":1,", kRunTimeoutMs), "\"seq\":1,"))
      << watch.error_output();
  writer().publish(sample_pose(2));
  EXPECT_EQ(watch.wait_exit(kRunTimeoutMs), 0) << watch.error_output();
  EXPECT_EQ(count_lines(watch.output()), 2u) << watch.output();
}

TEST_F(CtlCommands, WatchReattachesAcrossDaemonRestart) {
  ASSERT_NO_FATAL_FAILURE(start());
  writer().publish(sample_pose(1));
  test::ChildProcess watch(ctl({"watch", "--shm", name(), "--json", "--count", "2"}),
                           capturing_stderr());
  ASSERT_TRUE(watch.started()) << watch.start_error();
  ASSERT_TRUE(contains(watch.read_until("\"seq\":1,", kRunTimeoutMs), "\"seq\":1,"))
      << watch.error_output();
  writer_.reset();  // the first daemon stops cleanly
  ShmOptions options;
  options.name = name();
  auto second = ShmPoseWriter::create(options);
  ASSERT_TRUE(second) << second.error().message;
  ASSERT_TRUE(contains(watch.read_error_until("re-attached", kRunTimeoutMs), "re-attached"))
      << watch.error_output();
  second->publish(sample_pose(7));
  EXPECT_EQ(watch.wait_exit(kRunTimeoutMs), 0) << watch.error_output();
  EXPECT_EQ(count_lines(watch.output()), 2u) << watch.output();
  EXPECT_TRUE(contains(watch.output(), "\"timestamp_ns\":7")) << watch.output();
}

// Issue 28, defect 9: watch printed a dead daemon's last pose as valid and
// exited 0. The last pose of a stopped daemon is not shown; the next
// daemon's are.
TEST_F(CtlCommands, WatchDoesNotShowAStoppedDaemonsLastPoseAsCurrent) {
  ASSERT_NO_FATAL_FAILURE(start());
  writer().publish(sample_pose(1));
  writer().mark_stopped();
  test::ChildProcess watch(ctl({"watch", "--shm", name(), "--json", "--count", "1"}),
                           capturing_stderr());
  ASSERT_TRUE(watch.started()) << watch.start_error();
  ASSERT_TRUE(contains(watch.read_error_until("is not shown", kRunTimeoutMs), "is not shown"))
      << watch.error_output();
  writer_.reset();
  ShmOptions options;
  options.name = name();
  auto second = ShmPoseWriter::create(options);
  ASSERT_TRUE(second) << second.error().message;
  second->publish(sample_pose(7));
  EXPECT_EQ(watch.wait_exit(kRunTimeoutMs), 0) << watch.error_output();
  EXPECT_EQ(count_lines(watch.output()), 1u) << watch.output();
  EXPECT_TRUE(contains(watch.output(), "\"timestamp_ns\":7")) << watch.output();
}

// Issue 15: garbage over a live segment (0x5a everywhere: a consistent
// seqlock with seq 0x5a5a...) made an attached watch print one garbage pose
// and then wait for the writer to pass 6.5e18: every later pose skipped,
// silently. Now it follows the writer's sequence again and says why. No
// heartbeat thread (it would repair the garbage), so the writer's staleness
// threshold is long: a loaded sanitizer run started watch more than the
// default 500 ms after the first pose, and watch rightly called it stale.
TEST_F(CtlCommands, WatchFollowsTheWriterAfterGarbageOverTheSegmentAndSaysSo) {
  ASSERT_NO_FATAL_FAILURE(start(/*heartbeat_period_ms=*/0, /*stale_after_ms=*/60'000));
  writer().publish(sample_pose(1));
  test::ChildProcess watch(ctl({"watch", "--shm", name(), "--json", "--count", "3"}),
                           capturing_stderr());
  ASSERT_TRUE(watch.started()) << watch.start_error();
  ASSERT_TRUE(contains(watch.read_until("\"seq\":1,", kRunTimeoutMs), "\"seq\":1,"))
      << watch.error_output();
  {
    const int fd = ::shm_open(name().c_str(), O_RDWR | O_CLOEXEC, 0);
    ASSERT_GE(fd, 0);
    void* p = ::mmap(nullptr, sizeof(shm::Segment), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    ::close(fd);
    ASSERT_NE(p, MAP_FAILED);
    std::memset(p, 0x5a, sizeof(shm::Segment));
    ::munmap(p, sizeof(shm::Segment));
  }
  // Longer than the watch's 250 ms liveness slice: it wakes and reads the garbage.
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  writer().heartbeat();                // restores the header's identity
  constexpr int64_t kSeqEnd = 10'000;  // the writer's own poses are 2..kSeqEnd-1
  std::atomic<bool> finished{false};
  std::thread publisher([&] {
    for (int64_t k = 2; !finished.load() && k < kSeqEnd; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      writer().publish(sample_pose(k));
    }
  });
  const int rc = watch.wait_exit(kRunTimeoutMs);
  finished.store(true);
  publisher.join();
  EXPECT_EQ(rc, 0) << watch.error_output();
  EXPECT_TRUE(contains(watch.error_output(), "went back from"))
      << watch.error_output() << watch.output();
  EXPECT_TRUE(contains(watch.error_output(), "something other than ceilposed wrote into"));
  // The last line is one of the writer's own poses again (2..9999): under
  // load the watch may wake only after a few of them, so not necessarily 2.
  const std::string out = watch.output();
  const std::string seq_key = "{\"seq\":";
  const std::size_t last = out.rfind(seq_key);
  ASSERT_NE(last, std::string::npos) << out;
  const long long seq = std::strtoll(out.c_str() + last + seq_key.size(), nullptr, 10);
  EXPECT_GE(seq, 2) << "the writer's own poses again: " << out;
  EXPECT_LT(seq, kSeqEnd) << "the writer's own poses again: " << out;
}

TEST_F(CtlCommands, WatchTablePrintsHeaderAndRows) {
  ASSERT_NO_FATAL_FAILURE(start());
  for (int64_t k = 1; k <= 2; ++k) writer().publish(sample_pose(k));
  EXPECT_EQ(run({"watch", "--shm", name(), "--count", "1"}), 0) << err_;
  EXPECT_TRUE(contains(out_, "yaw_deg")) << out_;
  EXPECT_TRUE(contains(out_, "1.2500")) << out_;
}

}  // namespace
}  // namespace ceilpose
