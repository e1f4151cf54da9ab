// The C API over a live writer: codes, messages, and the example program.
#include <gtest/gtest.h>

#include <atomic>
#include <set>
#include <string>

#include "ceilpose/pose_client.h"
#include "ipc/shm/shm_pose_writer.h"
#include "shm_test_support.h"
#include "tests/support/child_process.h"

namespace ceilpose {
namespace {

using test::check_pose;
using test::is_consistent;

class CClient : public test::ShmFixture {};

struct ClientCloser {
  void operator()(ceilpose_client* c) const { ceilpose_client_close(c); }
};
using ClientPtr = std::unique_ptr<ceilpose_client, ClientCloser>;

ClientPtr open_client(const std::string& name) {
  ceilpose_client* raw = nullptr;
  const int rc = ceilpose_client_open(name.c_str(), &raw);
  EXPECT_EQ(rc, CEILPOSE_OK) << ceilpose_last_error_message();
  return ClientPtr(raw);
}

TEST_F(CClient, OpenOfMissingSegmentReturnsNotFoundWithMessageNamingIt) {
  ceilpose_client* c = nullptr;
  EXPECT_EQ(ceilpose_client_open(name().c_str(), &c), CEILPOSE_ERR_NOT_FOUND);
  EXPECT_EQ(c, nullptr);
  EXPECT_NE(std::string(ceilpose_last_error_message()).find(name()), std::string::npos);
}

// Issue 28, defect 16: a timeout on a good client reported the earlier
// "no shm segment" of another open.
TEST_F(CClient, TheLastErrorIsTheLastCallsNotAnOlderOne) {
  ASSERT_NO_FATAL_FAILURE(start());
  ceilpose_client* missing = nullptr;
  ASSERT_EQ(ceilpose_client_open("/ceilpose-no-such-segment", &missing), CEILPOSE_ERR_NOT_FOUND);
  ClientPtr client = open_client(name());
  ASSERT_NE(client, nullptr);
  EXPECT_STREQ(ceilpose_last_error_message(), "") << "the open succeeded";
  ceilpose_pose p;
  EXPECT_EQ(ceilpose_client_wait_next(client.get(), 0, 10, &p), CEILPOSE_ERR_TIMEOUT);
  EXPECT_STREQ(ceilpose_last_error_message(), ceilpose_strerror(CEILPOSE_ERR_TIMEOUT));
}

TEST(CClientModeName, NamesEveryModeAsSpecPrintsIt) {
  EXPECT_STREQ(ceilpose_mode_name(CEILPOSE_MODE_AUTO), "auto");
  EXPECT_STREQ(ceilpose_mode_name(CEILPOSE_MODE_AXES), "axes");
  EXPECT_STREQ(ceilpose_mode_name(CEILPOSE_MODE_BARYCENTRIC), "barycentric");
  EXPECT_STREQ(ceilpose_mode_name(CEILPOSE_MODE_LSQ), "lsq");
  EXPECT_STREQ(ceilpose_mode_name(200), "unknown");
}

TEST_F(CClient, NullArgumentsAreInvalid) {
  EXPECT_EQ(ceilpose_client_open("/x", nullptr), CEILPOSE_ERR_INVALID_ARGUMENT);
  ceilpose_pose p;
  EXPECT_EQ(ceilpose_client_read_latest(nullptr, &p), CEILPOSE_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(ceilpose_client_wait_next(nullptr, 0, 0, &p), CEILPOSE_ERR_INVALID_ARGUMENT);
  ceilpose_client_close(nullptr);
}

TEST_F(CClient, ReadsLatestPoseStatusAndWriterInfo) {
  ASSERT_NO_FATAL_FAILURE(start());
  ClientPtr client = open_client(name());
  ASSERT_NE(client, nullptr);
  ceilpose_client* raw = client.get();

  ceilpose_pose p;
  EXPECT_EQ(ceilpose_client_read_latest(raw, &p), CEILPOSE_ERR_NO_POSE);
  writer().publish(check_pose(1));
  writer().publish(check_pose(2));
  ASSERT_EQ(ceilpose_client_read_latest(raw, &p), CEILPOSE_OK);
  EXPECT_EQ(p.seq, 2u);
  EXPECT_TRUE(is_consistent(p));

  StatusRecord s{};
  s.fps = 30.0;
  s.frames = 42;
  s.fix_state = CEILPOSE_FIX_OK;
  set_status_source(&s, "synthetic");
  writer().update_status(s);
  ceilpose_status cs;
  ASSERT_EQ(ceilpose_client_read_status(raw, &cs), CEILPOSE_OK);
  EXPECT_EQ(cs.frames, 42u);
  EXPECT_STREQ(cs.source, "synthetic");

  ceilpose_writer_info info;
  ASSERT_EQ(ceilpose_client_writer_info(raw, &info), CEILPOSE_OK);
  EXPECT_EQ(info.pid, ::getpid());
  EXPECT_EQ(info.generation, writer().generation());
  EXPECT_EQ(info.state, static_cast<uint32_t>(CEILPOSE_STATE_RUNNING));

  ceilpose_liveness live;
  ASSERT_EQ(ceilpose_client_liveness(raw, 1000, &live), CEILPOSE_OK);
  EXPECT_EQ(live, CEILPOSE_LIVE);
}

TEST_F(CClient, WaitNextReturnsPoseThenTimesOut) {
  ASSERT_NO_FATAL_FAILURE(start());
  ClientPtr client = open_client(name());
  ASSERT_NE(client, nullptr);
  ceilpose_client* raw = client.get();
  writer().publish(check_pose(1));
  ceilpose_pose p;
  EXPECT_EQ(ceilpose_client_wait_next(raw, 0, 1000, &p), CEILPOSE_OK);
  EXPECT_EQ(p.seq, 1u);
  EXPECT_EQ(ceilpose_client_wait_next(raw, 1, 50, &p), CEILPOSE_ERR_TIMEOUT);
  writer().mark_stopped();
  EXPECT_EQ(ceilpose_client_wait_next(raw, 1, 1000, &p), CEILPOSE_ERR_STOPPED);
}

TEST_F(CClient, ReadRecentReturnsNewestFirst) {
  ASSERT_NO_FATAL_FAILURE(start());
  ClientPtr client = open_client(name());
  ASSERT_NE(client, nullptr);
  ceilpose_client* raw = client.get();
  for (uint64_t k = 1; k <= 10; ++k) writer().publish(check_pose(k));
  ceilpose_pose recent[4];
  uint32_t n = 0;
  ASSERT_EQ(ceilpose_client_read_recent(raw, recent, 4, &n), CEILPOSE_OK);
  ASSERT_EQ(n, 4u);
  EXPECT_EQ(recent[0].seq, 10u);
  EXPECT_EQ(recent[3].seq, 7u);
}

// A pose from the filter: at x = 1 m, driving East at 0.5 m/s, accelerating
// North at 2 m/s², turning at 1 rad/s; 1 mm / 0.1 m/s / 1 m/s² sigmas.
PoseRecord moving_pose(int64_t capture_ns) {
  PoseRecord p{};
  p.capture_mono_ns = capture_ns;
  p.x_m = 1.0;
  p.y_m = 2.0;
  p.yaw_rad = 0.5;
  p.flags = kPoseValid | kPoseFiltered;
  MotionEstimate m;
  m.valid = true;
  m.time_ns = capture_ns;
  m.state.x = {1.0, 2.0, 0.5, 0.5, 0.0, 1.0, 0.0, 2.0, 0.0};
  const double sigma[kMotionStates] = {1e-3, 1e-3, 1e-3, 0.1, 0.1, 0.1, 1.0, 1.0, 1.0};
  for (int i = 0; i < kMotionStates; ++i) m.state.p[i * kMotionStates + i] = sigma[i] * sigma[i];
  m.jerk = {100.0, 100.0, 100.0};
  m.horizon_ms = 200.0;
  set_pose_motion(&p, m);
  return p;
}

TEST_F(CClient, PredictCarriesTheLatestPoseToTheAskedInstant) {
  ASSERT_NO_FATAL_FAILURE(start());
  ClientPtr client = open_client(name());
  ceilpose_pose p;
  EXPECT_EQ(ceilpose_client_predict(client.get(), 0, &p), CEILPOSE_ERR_NO_POSE);
  const int64_t t0 = 5'000'000'000;
  writer().publish(moving_pose(t0));
  ASSERT_EQ(ceilpose_client_predict(client.get(), t0 + 100'000'000, &p), CEILPOSE_OK);
  // x + v t, y + a t²/2, yaw + w t at t = 0.1 s.
  EXPECT_NEAR(p.x_m, 1.05, 1e-12);
  EXPECT_NEAR(p.y_m, 2.01, 1e-12);
  EXPECT_NEAR(p.yaw_rad, 0.6, 1e-12);
  EXPECT_NEAR(p.vy_mps, 0.2, 1e-12);
  EXPECT_EQ(p.capture_mono_ns, t0) << "the frame it came from";
  // Var x = σx² + t²σv² + t⁴/4 σa² + q t⁵/20.
  const double var_x = 1e-6 + 0.01 * 0.01 + 1e-4 / 4 + 100.0 * 1e-5 / 20;
  EXPECT_NEAR(p.covariance[0], var_x, 1e-12);
  EXPECT_NEAR(p.state_covariance[0], var_x, 1e-12);
  EXPECT_GT(p.state_covariance[3 * 9 + 3], 0.01) << "velocity variance grows too";
  // Backwards within the horizon works; beyond it is refused, pose untouched.
  ASSERT_EQ(ceilpose_client_predict(client.get(), t0 - 50'000'000, &p), CEILPOSE_OK);
  EXPECT_NEAR(p.x_m, 0.975, 1e-12);
  EXPECT_EQ(ceilpose_client_predict(client.get(), t0 + 200'000'001, &p), CEILPOSE_ERR_HORIZON);
  EXPECT_EQ(p.x_m, 1.0);
  EXPECT_EQ(ceilpose_client_predict(client.get(), INT64_MIN, &p), CEILPOSE_ERR_HORIZON);
  // An unfiltered or invalid latest pose has nothing to carry.
  PoseRecord still = moving_pose(t0 + 1);
  set_pose_motion(&still, MotionEstimate{});
  writer().publish(still);
  EXPECT_EQ(ceilpose_client_predict(client.get(), t0 + 1, &p), CEILPOSE_ERR_NO_MOTION);
  EXPECT_EQ(ceilpose_client_predict(nullptr, t0, &p), CEILPOSE_ERR_INVALID_ARGUMENT);
}

TEST_F(CClient, EveryErrorCodeHasItsOwnText) {
  std::set<std::string> texts;
  for (int code = CEILPOSE_OK; code >= CEILPOSE_ERR_HORIZON; --code) {
    texts.insert(ceilpose_strerror(code));
  }
  EXPECT_EQ(texts.size(), static_cast<size_t>(1 - CEILPOSE_ERR_HORIZON));
  EXPECT_EQ(texts.count(ceilpose_strerror(-1000)), 0u);
}

TEST_F(CClient, ExamplePrinterPrintsPublishedPoses) {
  ASSERT_NO_FATAL_FAILURE(start());
  for (uint64_t k = 1; k <= 3; ++k) writer().publish(check_pose(k));
  // Poses keep coming until the printer has its three: a printer slow to
  // start (ASan on a loaded machine) may attach after a fixed few were out.
  std::atomic<bool> done{false};
  std::thread more([&] {
    for (uint64_t k = 4; k <= 1000 && !done.load(); ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(30));
      writer().publish(check_pose(k));
    }
  });
  const test::RunOutput r =
      test::run_to_end({CEILPOSE_POSE_PRINTER_PATH, "--shm", name(), "--count", "3"}, 30'000);
  done.store(true);
  more.join();
  EXPECT_EQ(r.exit_code, 0) << r.err << r.failure;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 3) << r.out;
  EXPECT_NE(r.out.find("seq"), std::string::npos) << r.out;
}

TEST_F(CClient, ExamplePrinterExitsNoDaemonWhenSegmentMissing) {
  const test::RunOutput r = test::run_to_end({CEILPOSE_POSE_PRINTER_PATH, "--shm", name()}, 30'000);
  EXPECT_EQ(r.exit_code, 3) << r.err << r.failure;
  EXPECT_NE(r.err.find(name()), std::string::npos) << r.err;
}

}  // namespace
}  // namespace ceilpose
