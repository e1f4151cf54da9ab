#include "ipc/dds/dds_options.h"

#include <gtest/gtest.h>

namespace ceilpose {
namespace {

TEST(DdsOptions, AcceptsLegalRosNames) {
  EXPECT_TRUE(is_valid_ros_name("robot7"));
  EXPECT_TRUE(is_valid_ros_name("_hidden"));
  EXPECT_TRUE(is_valid_ros_name("Robot_7_a"));
}

TEST(DdsOptions, RejectsIllegalRosNames) {
  EXPECT_FALSE(is_valid_ros_name(""));
  EXPECT_FALSE(is_valid_ros_name("7robot"));
  EXPECT_FALSE(is_valid_ros_name("robot-7"));
  EXPECT_FALSE(is_valid_ros_name("robot.local"));
  EXPECT_FALSE(is_valid_ros_name("a__b"));
  EXPECT_FALSE(is_valid_ros_name("a/b"));
  EXPECT_TRUE(is_valid_ros_name(std::string(63, 'r')));
  EXPECT_FALSE(is_valid_ros_name(std::string(64, 'r'))) << "one length rule: 63 characters";
}

TEST(DdsOptions, ToRosNameTurnsHostNamesIntoLegalNames) {
  EXPECT_EQ(to_ros_name("robot-7.lab"), "robot_7_lab");
  EXPECT_EQ(to_ros_name("7up"), "r7up");
  EXPECT_EQ(to_ros_name("a--b"), "a_b");
  EXPECT_TRUE(is_valid_ros_name(to_ros_name("robot-7.lab")));
  EXPECT_EQ(to_ros_name(std::string(80, 'h')), std::string(63, 'h')) << "a long host name";
}

TEST(DdsOptions, TopicNamesFollowRos2Mangling) {
  EXPECT_EQ(pose_topic_name("alpha"), "rt/alpha/pose");
  EXPECT_EQ(status_topic_name("alpha"), "rt/alpha/ceilpose_status");
}

TEST(DdsOptions, RobotFromPoseTopicAcceptsOnlyRtRobotPose) {
  EXPECT_EQ(robot_from_pose_topic("rt/alpha/pose"), "alpha");
  EXPECT_EQ(robot_from_pose_topic("rt/alpha/ceilpose_status"), "");
  EXPECT_EQ(robot_from_pose_topic("rt//pose"), "");
  EXPECT_EQ(robot_from_pose_topic("rt/a/b/pose"), "");
  EXPECT_EQ(robot_from_pose_topic("rq/alpha/pose"), "");
}

TEST(DdsOptions, ValidateNamesTheBadRobotName) {
  DdsOptions options;
  options.robot = "robot-7";
  const auto ok = validate(options);
  ASSERT_FALSE(ok.ok());
  EXPECT_NE(ok.error().message.find("'robot-7'"), std::string::npos) << ok.error().message;
  EXPECT_NE(ok.error().message.find("robot_7"), std::string::npos) << ok.error().message;
}

TEST(DdsOptions, ValidateRejectsDomainIdAbove230) {
  DdsOptions options;
  options.robot = "alpha";
  options.domain.domain_id = 231;
  const auto ok = validate(options);
  ASSERT_FALSE(ok.ok());
  EXPECT_NE(ok.error().message.find("231"), std::string::npos);
}

TEST(DdsOptions, ValidateRejectsZeroHistoryDepth) {
  DdsOptions options;
  options.robot = "alpha";
  options.history_depth = 0;
  EXPECT_FALSE(validate(options).ok());
}

TEST(DdsOptions, ValidateRejectsXmlMetacharactersInInterfaceNames) {
  DdsDomainOptions options;
  options.interfaces = {"eth0\"/><x"};
  const auto ok = validate(options);
  ASSERT_FALSE(ok.ok());
  EXPECT_NE(ok.error().message.find("interface"), std::string::npos);
}

TEST(DdsOptions, ConfigXmlCarriesInterfacesPeersAndMulticast) {
  DdsDomainOptions options;
  options.interfaces = {"lo", "192.168.1.5"};
  options.peers = {"127.0.0.1"};
  options.allow_multicast = false;
  const std::string xml = cyclone_config_xml(options);
  EXPECT_NE(xml.find("<NetworkInterface name=\"lo\"/>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<NetworkInterface address=\"192.168.1.5\"/>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<Peer address=\"127.0.0.1\"/>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<ParticipantIndex>auto</ParticipantIndex>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<MaxAutoParticipantIndex>63</MaxAutoParticipantIndex>"), std::string::npos)
      << "64 participants a host by default, not Cyclone's 10: " << xml;
  EXPECT_NE(xml.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos) << xml;
}

TEST(DdsOptions, NoExplicitDomainWithoutNetworkOptions) {
  DdsDomainOptions options;
  EXPECT_FALSE(options.needs_explicit_domain());
  options.peers = {"127.0.0.1"};
  EXPECT_TRUE(options.needs_explicit_domain());
}

}  // namespace
}  // namespace ceilpose
