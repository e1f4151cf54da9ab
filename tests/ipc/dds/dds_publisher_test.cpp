#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "core/clock.h"
#include "ipc/dds/dds_pose_publisher.h"
#include "tests/ipc/dds/dds_test_env.h"

namespace ceilpose {
namespace {

class DdsPublisher : public ::testing::Test {
 protected:
  void SetUp() override {
    test::use_loopback_dds();
    options_.robot = test::unique_robot_name("unit");
    options_.domain.domain_id = test::unique_domain_id();
  }
  DdsOptions options_;
};

TEST_F(DdsPublisher, CreateRejectsIllegalRobotNameNamingIt) {
  options_.robot = "robot-7";
  auto pub = DdsPosePublisher::create(options_);
  ASSERT_FALSE(pub.ok());
  EXPECT_NE(pub.error().message.find("robot-7"), std::string::npos) << pub.error().message;
}

TEST_F(DdsPublisher, TopicsCarryTheRobotName) {
  auto pub = DdsPosePublisher::create(options_);
  ASSERT_TRUE(pub.ok()) << pub.error().message;
  EXPECT_EQ(pub->pose_topic(), "rt/" + options_.robot + "/pose");
  EXPECT_EQ(pub->status_topic(), "rt/" + options_.robot + "/ceilpose_status");
}

TEST_F(DdsPublisher, InvalidPoseIsRefusedNotPublished) {
  auto pub = DdsPosePublisher::create(options_);
  ASSERT_TRUE(pub.ok()) << pub.error().message;
  DdsPose pose;
  pose.valid = false;
  const auto refused = pub->publish(pose);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("invalid pose"), std::string::npos);
  pose.valid = true;
  EXPECT_TRUE(pub->publish(pose).ok());
  EXPECT_EQ(pub->published(), 1u);
}

TEST_F(DdsPublisher, StatusWithoutFixReachesAReaderWithItsFigures) {
  auto pub = DdsPosePublisher::create(options_);
  ASSERT_TRUE(pub.ok()) << pub.error().message;
  auto participant = DdsParticipant::create(options_.domain);
  ASSERT_TRUE(participant.ok()) << participant.error().message;
  const dds_entity_t topic =
      dds_create_topic(participant->handle(), &ceilpose_msg_dds__Status__desc,
                       pub->status_topic().c_str(), nullptr, nullptr);
  ASSERT_GT(topic, 0);
  const dds_entity_t reader = dds_create_reader(participant->handle(), topic, nullptr, nullptr);
  ASSERT_GT(reader, 0);
  DdsStatus status;
  status.fix = false;
  status.health = DdsHealth::kDegraded;
  status.fps = 12.5f;
  status.drops = 7;
  status.latency_p99_us = 900;

  // The writer drops what it writes before it has matched the reader: keep
  // publishing (bounded) until a sample arrives.
  ceilpose_msg_dds__Status_ msg{};
  void* samples[1] = {&msg};
  dds_sample_info_t info{};
  bool received = false;
  const int64_t deadline_ns = monotonic_ns() + 10'000'000'000;
  while (!received && monotonic_ns() < deadline_ns) {
    ASSERT_TRUE(pub->publish_status(status).ok());
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    received = dds_take(reader, samples, &info, 1, 1) == 1 && info.valid_data;
  }

  ASSERT_TRUE(received);
  EXPECT_FALSE(msg.fix);
  EXPECT_EQ(msg.health, static_cast<uint8_t>(DdsHealth::kDegraded));
  EXPECT_STREQ(msg.robot, options_.robot.c_str());
  EXPECT_FLOAT_EQ(msg.fps, 12.5f);
  EXPECT_EQ(msg.drops, 7u);
  EXPECT_EQ(msg.latency_p99_us, 900u);
  dds_sample_free(&msg, &ceilpose_msg_dds__Status__desc, DDS_FREE_CONTENTS);
}

TEST_F(DdsPublisher, DisposedPublisherRefusesToPublish) {
  auto pub = DdsPosePublisher::create(options_);
  ASSERT_TRUE(pub.ok()) << pub.error().message;
  pub->dispose();
  DdsPose pose;
  pose.valid = true;
  const auto ok = pub->publish(pose);
  ASSERT_FALSE(ok.ok());
  EXPECT_NE(ok.error().message.find("disposed"), std::string::npos);
  pub->dispose();  // idempotent
}

TEST_F(DdsPublisher, MovedFromPublisherDoesNotTearDownTheMovedTo) {
  auto pub = DdsPosePublisher::create(options_);
  ASSERT_TRUE(pub.ok()) << pub.error().message;
  DdsPosePublisher moved = std::move(pub.value());
  { DdsPosePublisher sink = std::move(moved); }
  // `pub` and `moved` are empty now; a fresh publisher on the same domain works.
  auto again = DdsPosePublisher::create(options_);
  ASSERT_TRUE(again.ok()) << again.error().message;
  DdsPose pose;
  pose.valid = true;
  EXPECT_TRUE(again->publish(pose).ok());
}

TEST_F(DdsPublisher, SecondExplicitDomainConfigInOneProcessIsReportedClearly) {
  options_.domain.peers = {"127.0.0.1"};
  auto first = DdsPosePublisher::create(options_);
  ASSERT_TRUE(first.ok()) << first.error().message;
  auto second = DdsPosePublisher::create(options_);
  ASSERT_FALSE(second.ok());
  EXPECT_NE(second.error().message.find("already exists"), std::string::npos)
      << second.error().message;
}

}  // namespace
}  // namespace ceilpose
