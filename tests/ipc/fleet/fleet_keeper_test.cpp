// What of the fleet's samples reaches a controller, read back through the C
// client as a controller reads it; the clock is passed in.
#include "ipc/fleet/fleet_keeper.h"

#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "ceilpose/pose_client.h"
#include "ipc/shm/shm_fleet_writer.h"
#include "tests/ipc/fleet/fleet_test_support.h"

namespace ceilpose {
namespace {

using test::kMonoNow;
using test::kMs;
using test::kRealNow;
using test::moving_pose;

class FleetKeeperTest : public ::testing::Test {
 protected:
  void start(uint32_t capacity = 8, FleetOptions options = {}) {
    shm_ = test::unique_fleet_shm();
    ShmFleetOptions o;
    o.name = fleet_segment_name(shm_);
    o.capacity = capacity;
    o.stale_after_ms = static_cast<uint32_t>(options.stale_after_ms);
    auto w = ShmFleetWriter::create(o);
    ASSERT_TRUE(w.ok()) << w.error().message;
    writer_.emplace(std::move(w).value());
    keeper_.emplace(&*writer_, options, [this](FleetEvent e, const std::string& message) {
      events_.push_back({e, message});
    });
    ASSERT_EQ(ceilpose_client_fleet_open(shm_.c_str(), &client_), CEILPOSE_OK)
        << ceilpose_last_error_message();
  }
  void TearDown() override {
    ceilpose_client_fleet_close(client_);
    if (writer_) {
      EXPECT_TRUE(ShmFleetWriter::remove(writer_->name()).ok());
    }
  }

  void give(const std::string& robot, uint64_t writer, const PoseRecord& pose,
            int64_t now_mono = kMonoNow, int64_t now_real = kRealNow) {
    names_.push_back(robot);  // FleetSample points at the name during the call only
    FleetSample s;
    s.robot = &names_.back();
    s.writer = writer;
    s.pose = pose;
    keeper_->accept(s, now_mono, now_real);
  }

  std::vector<ceilpose_fleet_robot> read(int64_t t_mono_ns = 0) {
    std::vector<ceilpose_fleet_robot> out(64);
    uint32_t n = 0;
    EXPECT_EQ(ceilpose_client_fleet_read(client_, t_mono_ns, out.data(), 64, &n), CEILPOSE_OK);
    out.resize(n);
    return out;
  }
  ceilpose_fleet_info info() {
    ceilpose_fleet_info i{};
    EXPECT_EQ(ceilpose_client_fleet_info(client_, &i), CEILPOSE_OK);
    return i;
  }
  size_t events_of(FleetEvent kind) const {
    size_t n = 0;
    for (const auto& [e, m] : events_) n += e == kind ? 1 : 0;
    return n;
  }

  std::string shm_;
  std::optional<ShmFleetWriter> writer_;
  std::optional<FleetKeeper> keeper_;
  ceilpose_fleet* client_ = nullptr;
  std::deque<std::string> names_;
  std::vector<std::pair<FleetEvent, std::string>> events_;
};

TEST_F(FleetKeeperTest, ANeighbourArrivesOnThisRobotsClockWithItsLatency) {
  start();
  // Exposed 12 ms before it arrived (realtime), so 12 ms before now here.
  give("rb", 7, moving_pose(kRealNow - 12 * kMs, 1.5));
  const auto robots = read();
  ASSERT_EQ(robots.size(), 1u);
  const ceilpose_fleet_robot& r = robots[0];
  EXPECT_STREQ(r.robot, "rb");
  EXPECT_EQ(r.pose.capture_mono_ns, kMonoNow - 12 * kMs);
  EXPECT_EQ(r.pose.capture_real_ns, kRealNow - 12 * kMs);
  EXPECT_EQ(r.latency_ns, 12 * kMs);
  EXPECT_EQ(r.received_mono_ns, kMonoNow);
  EXPECT_EQ(r.samples, 1u);
  EXPECT_DOUBLE_EQ(r.pose.x_m, 1.5);
  EXPECT_EQ(info().robots, 1u);
  EXPECT_EQ(info().accepted, 1u);
  EXPECT_EQ(events_of(FleetEvent::kJoined), 1u);
  ceilpose_fleet_robot found{};
  EXPECT_EQ(ceilpose_client_fleet_find(client_, "rb", 0, &found), CEILPOSE_OK);
  EXPECT_EQ(found.pose.capture_mono_ns, r.pose.capture_mono_ns);
  EXPECT_EQ(ceilpose_client_fleet_find(client_, "nobody", 0, &found), CEILPOSE_ERR_NO_POSE);
}

TEST_F(FleetKeeperTest, PredictionIsTheOwnPosesModelAndHorizon) {
  start();
  const PoseRecord sent = moving_pose(kRealNow - 10 * kMs, 1.0);
  give("rb", 7, sent);
  const int64_t exposure_mono = kMonoNow - 10 * kMs;
  // 100 ms after the exposure at 0.5 m/s: 5 cm east, covariance grown.
  const auto ahead = read(exposure_mono + 100 * kMs);
  ASSERT_EQ(ahead.size(), 1u);
  EXPECT_TRUE(ahead[0].fleet_flags & CEILPOSE_FLEET_PREDICTED);
  PoseRecord own = sent;
  own.capture_mono_ns = exposure_mono;
  PoseRecord expected;
  ASSERT_EQ(predict_pose(own, exposure_mono + 100 * kMs, &expected), PredictResult::kOk);
  EXPECT_DOUBLE_EQ(ahead[0].pose.x_m, expected.x_m);
  EXPECT_NEAR(ahead[0].pose.x_m, 1.05, 1e-9);
  EXPECT_DOUBLE_EQ(ahead[0].pose.covariance[0], expected.covariance[0]);
  EXPECT_GT(ahead[0].pose.covariance[0], sent.covariance[0]);
  // Beyond its 500 ms horizon: as received, and said so.
  const auto far = read(exposure_mono + 800 * kMs);
  EXPECT_TRUE(far[0].fleet_flags & CEILPOSE_FLEET_NOT_PREDICTED);
  EXPECT_FALSE(far[0].fleet_flags & CEILPOSE_FLEET_PREDICTED);
  EXPECT_DOUBLE_EQ(far[0].pose.x_m, 1.0);
}

TEST_F(FleetKeeperTest, NonFiniteOrInvalidPosesNeverReachTheSegment) {
  start();
  PoseRecord nan_x = moving_pose(kRealNow, 1.0);
  nan_x.x_m = std::nan("");
  PoseRecord inf_cov = moving_pose(kRealNow, 1.0);
  inf_cov.state_covariance[40] = std::numeric_limits<double>::infinity();
  PoseRecord negative_variance = moving_pose(kRealNow, 1.0);
  negative_variance.covariance[4] = -1e-3;
  PoseRecord invalid = moving_pose(kRealNow, 1.0);
  invalid.flags = 0;
  for (const PoseRecord& p : {nan_x, inf_cov, negative_variance, invalid}) give("rbad", 1, p);
  EXPECT_TRUE(read().empty());
  EXPECT_EQ(info().refused_invalid, 4u);
  EXPECT_EQ(info().accepted, 0u);
  EXPECT_EQ(events_of(FleetEvent::kRefused), 1u) << "one report per robot and reason";
  give(std::string(70, 'n'), 2, moving_pose(kRealNow, 1.0));
  EXPECT_TRUE(read().empty());
  EXPECT_EQ(info().refused_invalid, 5u);
}

TEST_F(FleetKeeperTest, SamplesFromTheFutureOrTheDistantPastAreRefused) {
  FleetOptions o;
  o.max_clock_offset_ms = 200;
  o.stale_after_ms = 1000;
  start(8, o);
  give("rfuture", 1, moving_pose(kRealNow + 250 * kMs, 1.0));
  give("rpast", 2, moving_pose(kRealNow - 1300 * kMs, 1.0));
  EXPECT_TRUE(read().empty());
  EXPECT_EQ(info().refused_future, 1u);
  EXPECT_EQ(info().refused_past, 1u);
  // Within the allowed offset either way: shown, with a negative latency
  // when the other clock is ahead.
  give("rahead", 3, moving_pose(kRealNow + 150 * kMs, 1.0));
  give("rlate", 4, moving_pose(kRealNow - 1100 * kMs, 1.0));
  const auto robots = read();
  ASSERT_EQ(robots.size(), 2u);
  EXPECT_EQ(robots[0].latency_ns, -150 * kMs);
  EXPECT_NE(events_[0].second.find("future"), std::string::npos) << events_[0].second;
}

TEST_F(FleetKeeperTest, ASecondWriterUnderATakenNameIsRefusedUntilTheFirstIsStale) {
  FleetOptions o;
  o.stale_after_ms = 500;
  start(8, o);
  give("twin", 1, moving_pose(kRealNow, 1.0));
  give("twin", 2, moving_pose(kRealNow, 9.0));
  auto robots = read();
  ASSERT_EQ(robots.size(), 1u);
  EXPECT_DOUBLE_EQ(robots[0].pose.x_m, 1.0) << "the first writer keeps the slot";
  EXPECT_EQ(info().refused_duplicate, 1u);
  // The first goes quiet: stale, and the other writer (a restarted robot)
  // takes the same slot.
  keeper_->sweep(kMonoNow + 600 * kMs);
  give("twin", 2, moving_pose(kRealNow + 700 * kMs, 9.0), kMonoNow + 700 * kMs,
       kRealNow + 700 * kMs);
  robots = read();
  ASSERT_EQ(robots.size(), 1u);
  EXPECT_DOUBLE_EQ(robots[0].pose.x_m, 9.0);
  EXPECT_FALSE(robots[0].fleet_flags & CEILPOSE_FLEET_STALE);
}

TEST_F(FleetKeeperTest, MoreRobotsThanSlotsAreRefusedAndNoSlotIsOverwritten) {
  start(4);
  const std::vector<std::string> names{"r0", "r1", "r2", "r3", "r4", "r5"};
  for (int i = 0; i < 6; ++i) give(names[i], 10 + i, moving_pose(kRealNow, i));
  const auto robots = read();
  ASSERT_EQ(robots.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(std::string(robots[i].robot), names[i]);
    EXPECT_DOUBLE_EQ(robots[i].pose.x_m, i);
  }
  EXPECT_EQ(info().refused_full, 2u);
  EXPECT_EQ(info().robots, 4u);
  EXPECT_EQ(info().capacity, 4u);
  EXPECT_EQ(events_of(FleetEvent::kRefused), 2u);
  EXPECT_NE(events_.back().second.find("fleet.capacity"), std::string::npos);
}

TEST_F(FleetKeeperTest, AQuietRobotIsStaleThenRemovedAndItsSlotReused) {
  FleetOptions o;
  o.stale_after_ms = 500;
  o.remove_after_ms = 2000;
  start(2, o);
  give("ra", 1, moving_pose(kRealNow, 1.0));
  give("rb", 2, moving_pose(kRealNow, 2.0));
  keeper_->sweep(kMonoNow + 400 * kMs);
  EXPECT_FALSE(read()[0].fleet_flags & CEILPOSE_FLEET_STALE);
  keeper_->sweep(kMonoNow + 600 * kMs);
  EXPECT_TRUE(read()[0].fleet_flags & CEILPOSE_FLEET_STALE);
  EXPECT_EQ(events_of(FleetEvent::kStale), 2u);
  keeper_->sweep(kMonoNow + 2100 * kMs);
  EXPECT_TRUE(read().empty());
  EXPECT_EQ(info().removed, 2u);
  EXPECT_EQ(info().robots, 0u);
  give("rc", 3, moving_pose(kRealNow + 2200 * kMs, 3.0), kMonoNow + 2200 * kMs,
       kRealNow + 2200 * kMs);
  ASSERT_EQ(read().size(), 1u);
  EXPECT_STREQ(read()[0].robot, "rc");
}

TEST_F(FleetKeeperTest, AWriterThatLeavesMakesItsRobotStaleAtOnce) {
  start();
  give("ra", 1, moving_pose(kRealNow, 1.0));
  names_.push_back("ra");
  FleetSample left;
  left.robot = &names_.back();
  left.writer = 1;
  left.alive = false;
  keeper_->accept(left, kMonoNow + kMs, kRealNow + kMs);
  ASSERT_EQ(read().size(), 1u);
  EXPECT_TRUE(read()[0].fleet_flags & CEILPOSE_FLEET_STALE);
  EXPECT_DOUBLE_EQ(read()[0].pose.x_m, 1.0) << "the last pose stays, marked stale";
}

TEST_F(FleetKeeperTest, OnlyTheConfiguredRobotsAreKept) {
  FleetOptions o;
  o.robots = {"ra"};
  start(8, o);
  give("ra", 1, moving_pose(kRealNow, 1.0));
  give("rb", 2, moving_pose(kRealNow, 2.0));
  ASSERT_EQ(read().size(), 1u);
  EXPECT_STREQ(read()[0].robot, "ra");
}

TEST_F(FleetKeeperTest, GapsInTheSequenceAreCountedAsLost) {
  start();
  give("ra", 1, moving_pose(kRealNow, 1.0, 1));
  give("ra", 1, moving_pose(kRealNow, 1.0, 2));
  give("ra", 1, moving_pose(kRealNow, 1.0, 5));
  EXPECT_EQ(read()[0].lost, 2u);
  EXPECT_EQ(read()[0].samples, 3u);
}

}  // namespace
}  // namespace ceilpose
