#include <gtest/gtest.h>

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

TEST_F(DdsPublisher, InvalidPoseIsCountedNotPublished) {
  auto pub = DdsPosePublisher::create(options_);
  ASSERT_TRUE(pub.ok()) << pub.error().message;
  DdsPose pose;
  pose.valid = false;
  EXPECT_TRUE(pub->publish(pose).ok());
  pose.valid = true;
  EXPECT_TRUE(pub->publish(pose).ok());
  EXPECT_EQ(pub->skipped_invalid(), 1u);
  EXPECT_EQ(pub->published(), 1u);
}

TEST_F(DdsPublisher, StatusIsPublishedWithoutFix) {
  auto pub = DdsPosePublisher::create(options_);
  ASSERT_TRUE(pub.ok()) << pub.error().message;
  DdsStatus status;
  status.fix = false;
  status.health = DdsHealth::kDegraded;
  EXPECT_TRUE(pub->publish_status(status).ok());
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
