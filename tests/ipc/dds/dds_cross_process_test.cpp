// Poses cross process boundaries on a loopback-only domain of the test's own:
// ceilposectl fleet and the fake robot are separate programs.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/clock.h"
#include "ipc/dds/dds_fleet_listener.h"
#include "ipc/dds/dds_pose_publisher.h"
#include "tests/ipc/dds/dds_test_env.h"
#include "tests/support/child_process.h"

namespace ceilpose {
namespace {

using test::ChildProcess;
using test::number_field;
using test::robot_object;

constexpr char kPoseType[] = "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_";
// Generous bounds: discovery takes milliseconds on an idle machine but the
// suite also runs under ASan on two loaded cores.
constexpr int64_t kReadyTimeoutMs = 20'000;
constexpr int64_t kFleetTimeoutMs = 30'000;

class DdsCrossProcess : public ::testing::Test {
 protected:
  void SetUp() override {
    test::use_loopback_dds();
    domain_ = std::to_string(test::unique_domain_id());
  }

  std::vector<std::string> fake_robot(const std::string& robot, double x_m, double y_m,
                                      double yaw_rad) const {
    return {CEILPOSE_DDS_FAKE_ROBOT,
            "--robot",
            robot,
            "--domain",
            domain_,
            "--x",
            std::to_string(x_m),
            "--y",
            std::to_string(y_m),
            "--yaw",
            std::to_string(yaw_rad),
            "--rate",
            "50",
            "--duration",
            "60"};
  }

  std::vector<std::string> fleet_json(const char* duration_s) const {
    return {CEILPOSECTL, "fleet", "--json", "--duration", duration_s, "--domain", domain_};
  }

  std::string domain_;
};

TEST_F(DdsCrossProcess, SubscriberInAnotherProcessReceivesPublishedPose) {
  // Arrange: a publisher with explicit network options, layered on the
  // loopback CYCLONEDDS_URI, and ceilposectl fleet as the remote subscriber.
  DdsOptions options;
  options.robot = test::unique_robot_name("pub");
  options.domain.domain_id = static_cast<uint32_t>(std::stoul(domain_));
  options.domain.interfaces = {"lo"};
  options.domain.peers = {"127.0.0.1"};
  options.domain.allow_multicast = false;
  auto publisher = DdsPosePublisher::create(options);
  ASSERT_TRUE(publisher.ok()) << publisher.error().message;
  ChildProcess fleet(fleet_json("3"));
  ASSERT_TRUE(fleet.started());

  // Act: publish at 50 Hz while the subscriber listens.
  std::atomic<bool> stop{false};
  std::string publish_error;
  std::thread writer([&] {
    DdsPose pose;
    pose.valid = true;
    pose.pose = {3.6576, -1.2192, -2.5};
    while (!stop.load()) {
      pose.capture_realtime_ns = realtime_ns();
      if (auto ok = publisher->publish(pose); !ok) {
        publish_error = ok.error().message;
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  const int rc = fleet.wait_exit(kFleetTimeoutMs);
  stop = true;
  writer.join();

  // Assert
  ASSERT_TRUE(publish_error.empty()) << publish_error;
  ASSERT_EQ(rc, 0) << fleet.output();
  const std::string obj = robot_object(fleet.output(), options.robot);
  ASSERT_FALSE(obj.empty()) << fleet.output();
  EXPECT_NE(obj.find("\"topic\":\"rt/" + options.robot + "/pose\""), std::string::npos) << obj;
  EXPECT_NE(obj.find(std::string("\"type\":\"") + kPoseType + "\""), std::string::npos) << obj;
  EXPECT_NE(obj.find("\"encoding\":\"XCDR1\""), std::string::npos) << obj;
  EXPECT_NEAR(number_field(obj, "x_m"), 3.6576, 1e-6) << obj;
  EXPECT_NEAR(number_field(obj, "y_m"), -1.2192, 1e-6) << obj;
  EXPECT_NEAR(number_field(obj, "yaw_rad"), -2.5, 1e-6) << obj;
  EXPECT_GT(number_field(obj, "samples"), 0.0) << obj;
}

TEST_F(DdsCrossProcess, FleetSeesTwoPublishingRobotsAtOnce) {
  const std::string alpha = test::unique_robot_name("alpha");
  const std::string beta = test::unique_robot_name("beta");
  ChildProcess robot_a(fake_robot(alpha, 1.0, 2.0, 0.5));
  ChildProcess robot_b(fake_robot(beta, -4.0, 0.25, -1.0));
  ASSERT_NE(robot_a.read_until("ready", kReadyTimeoutMs).find("ready"), std::string::npos);
  ASSERT_NE(robot_b.read_until("ready", kReadyTimeoutMs).find("ready"), std::string::npos);

  ChildProcess fleet(fleet_json("3"));
  const int rc = fleet.wait_exit(kFleetTimeoutMs);

  ASSERT_EQ(rc, 0) << fleet.output();
  const std::string a = robot_object(fleet.output(), alpha);
  const std::string b = robot_object(fleet.output(), beta);
  ASSERT_FALSE(a.empty()) << fleet.output();
  ASSERT_FALSE(b.empty()) << fleet.output();
  EXPECT_NEAR(number_field(a, "x_m"), 1.0, 1e-6) << a;
  EXPECT_NEAR(number_field(a, "y_m"), 2.0, 1e-6) << a;
  EXPECT_NEAR(number_field(a, "yaw_rad"), 0.5, 1e-6) << a;
  EXPECT_NEAR(number_field(b, "x_m"), -4.0, 1e-6) << b;
  EXPECT_NEAR(number_field(b, "y_m"), 0.25, 1e-6) << b;
  EXPECT_NEAR(number_field(b, "yaw_rad"), -1.0, 1e-6) << b;
  // Poses arrive every 20 ms; a listener that stopped receiving would show
  // an age of the whole listening time.
  EXPECT_LT(number_field(a, "age_ms"), 2000.0) << a;
  EXPECT_LT(number_field(b, "age_ms"), 2000.0) << b;
}

TEST_F(DdsCrossProcess, FleetSaysNoRobotsSeenOnAnEmptyDomain) {
  ChildProcess fleet({CEILPOSECTL, "fleet", "--duration", "0.5", "--domain", domain_});
  const int rc = fleet.wait_exit(kFleetTimeoutMs);
  EXPECT_EQ(rc, 0) << fleet.output();
  EXPECT_NE(fleet.output().find("no robots seen on domain " + domain_ + " in 0.5 s"),
            std::string::npos)
      << fleet.output();
}

TEST_F(DdsCrossProcess, FleetListenerKeepsLatestPoseOfRobotInAnotherProcess) {
  const std::string robot = test::unique_robot_name("gamma");
  ChildProcess child(fake_robot(robot, 0.6096, 1.2192, 3.0));
  ASSERT_NE(child.read_until("ready", kReadyTimeoutMs).find("ready"), std::string::npos);
  DdsDomainOptions options;
  options.domain_id = static_cast<uint32_t>(std::stoul(domain_));
  auto listener = DdsFleetListener::create(options);
  ASSERT_TRUE(listener.ok()) << listener.error().message;

  const int64_t deadline_ns = monotonic_ns() + kReadyTimeoutMs * 1'000'000;
  std::vector<FleetRobot> robots;
  while (monotonic_ns() < deadline_ns) {
    ASSERT_TRUE(listener->poll(100).ok());
    robots = listener->robots();
    if (!robots.empty() && robots[0].samples >= 2) break;
  }

  ASSERT_EQ(robots.size(), 1u);
  EXPECT_EQ(robots[0].robot, robot);
  EXPECT_EQ(robots[0].topic, "rt/" + robot + "/pose");
  EXPECT_EQ(robots[0].type_name, kPoseType);
  ASSERT_GE(robots[0].samples, 2u);
  EXPECT_NEAR(robots[0].latest.pose.x_m, 0.6096, 1e-9);
  EXPECT_NEAR(robots[0].latest.pose.y_m, 1.2192, 1e-9);
  EXPECT_NEAR(robots[0].latest.pose.yaw_rad, 3.0, 1e-9);
  EXPECT_DOUBLE_EQ(robots[0].latest.covariance[8], 3e-3);
  // The stamp is the publisher's CLOCK_REALTIME at capture: recent.
  EXPECT_NEAR(static_cast<double>(robots[0].latest.capture_realtime_ns),
              static_cast<double>(realtime_ns()), 30e9);
}

// Issue 26: with unicast discovery (dds.peers) Cyclone's default lets 10
// participants share a host and the eleventh fails. ceilpose's own domain
// configuration allows dds.max_participants_per_host (64): twelve robots on
// one host all start.
TEST(DdsManyParticipants, TwelveRobotsWithUnicastPeersShareOneHost) {
  const std::string domain = std::to_string(test::unique_domain_id());
  std::vector<std::unique_ptr<ChildProcess>> robots;
  for (int k = 0; k < 12; ++k) {
    robots.push_back(std::make_unique<ChildProcess>(std::vector<std::string>{
        CEILPOSE_DDS_FAKE_ROBOT, "--robot",
        test::unique_robot_name("many") + "_" + std::to_string(k), "--domain", domain,
        "--interface", "lo", "--peer", "127.0.0.1", "--rate", "5", "--duration", "20"}));
  }
  for (auto& robot : robots) {
    EXPECT_NE(robot->read_until("ready", kReadyTimeoutMs).find("ready"), std::string::npos)
        << robot->output();
  }
}

}  // namespace
}  // namespace ceilpose
