// Issue 14: DDS Security on the wire, between processes on loopback. A
// robot's poses reach a subscriber of the same keystore, Cyclone's or Fast
// DDS's; a participant without credentials gets nothing; a robot's own
// identity cannot publish another robot's pose.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "tests/ipc/dds/dds_test_env.h"
#include "tests/keystore/test_keystore.h"
#include "tests/support/child_process.h"

namespace ceilpose {
namespace {

using test::ChildProcess;

constexpr int kReadyTimeoutMs = 20'000;
constexpr int kFleetTimeoutMs = 30'000;

class DdsSecurity : public ::testing::Test {
 protected:
  void SetUp() override {
    test::use_loopback_dds();
    domain_ = std::to_string(test::unique_domain_id());
  }

  // A robot publishing (2.5, -1.0) at 50 Hz as enclave `enclave` (or none).
  std::vector<std::string> fake_robot(const std::string& robot, const std::string& enclave) const {
    std::vector<std::string> args{CEILPOSE_DDS_FAKE_ROBOT,
                                  "--robot",
                                  robot,
                                  "--domain",
                                  domain_,
                                  "--x",
                                  "2.5",
                                  "--y",
                                  "-1.0",
                                  "--rate",
                                  "50",
                                  "--duration",
                                  "60"};
    if (!enclave.empty()) {
      for (const std::string& a :
           {std::string("--keystore"), keystore_.dir(), std::string("--enclave"), enclave})
        args.push_back(a);
    }
    return args;
  }

  std::vector<std::string> fleet_json(const std::string& enclave) const {
    std::vector<std::string> args{CEILPOSECTL, "fleet",    "--json", "--duration",
                                  "3",         "--domain", domain_};
    if (!enclave.empty()) {
      for (const std::string& a :
           {std::string("--keystore"), keystore_.dir(), std::string("--enclave"), enclave})
        args.push_back(a);
    }
    return args;
  }

  test::TestKeystore keystore_{"r1", "r2", "monitor"};
  std::string domain_;
};

TEST_F(DdsSecurity, AnAuthorisedSubscriberReceivesThePosesAndAPlainOneSeesNoRobot) {
  ChildProcess robot(fake_robot("r1", "r1"));
  ASSERT_NE(robot.read_until("ready", kReadyTimeoutMs).find("ready rt/r1/pose"), std::string::npos);

  ChildProcess secure(fleet_json("monitor"));
  ChildProcess plain(fleet_json(""));
  ASSERT_EQ(secure.wait_exit(kFleetTimeoutMs), 0) << secure.output();
  ASSERT_EQ(plain.wait_exit(kFleetTimeoutMs), 0) << plain.output();

  const std::string obj = test::robot_object(secure.output(), "r1");
  ASSERT_FALSE(obj.empty()) << secure.output();
  EXPECT_NEAR(test::number_field(obj, "x_m"), 2.5, 1e-9) << obj;
  EXPECT_NEAR(test::number_field(obj, "y_m"), -1.0, 1e-9) << obj;
  EXPECT_GT(test::number_field(obj, "samples"), 10.0) << obj;
  // Discovery itself is protected: the plain participant does not even learn
  // that the topic exists.
  EXPECT_NE(plain.output().find("\"robots\":[]"), std::string::npos) << plain.output();
}

TEST_F(DdsSecurity, ARobotsIdentityCannotPublishAnotherRobotsPose) {
  // r2 has a valid identity, but its permissions grant rt/r2/* only.
  auto forged = test::run_to_end(fake_robot("r1", "r2"), kReadyTimeoutMs);
  EXPECT_EQ(forged.exit_code, 1) << forged.err;
  EXPECT_NE(forged.err.find("cannot create a writer for DDS topic rt/r1/pose on domain " + domain_ +
                            ": Not Allowed By Security"),
            std::string::npos)
      << forged.err;
  EXPECT_EQ(forged.out.find("ready"), std::string::npos) << forged.out;
}

TEST_F(DdsSecurity, FastDdsWithTheKeystoreDecodesTheEncryptedPosesAndWithoutItGetsNothing) {
  ChildProcess robot(fake_robot("r1", "r1"));
  ASSERT_NE(robot.read_until("ready", kReadyTimeoutMs).find("ready"), std::string::npos);

  // Another vendor, as an SROS2 user's rmw_fastrtps would be set up.
  ChildProcess secure({CEILPOSE_FASTDDS_LISTENER, "--domain", domain_, "--topic", "rt/r1/pose",
                       "--count", "3", "--timeout-ms", "15000", "--enclave-dir",
                       keystore_.layout().enclave_dir("monitor")});
  ChildProcess plain({CEILPOSE_FASTDDS_LISTENER, "--domain", domain_, "--topic", "rt/r1/pose",
                      "--count", "1", "--timeout-ms", "4000"});
  EXPECT_EQ(secure.wait_exit(kFleetTimeoutMs), 0) << secure.output();
  const std::string& out = secure.output();
  EXPECT_NE(out.find("type=geometry_msgs::msg::dds_::PoseWithCovarianceStamped_"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("frame=map x=2.5 y=-1 z=0 "), std::string::npos) << out;

  EXPECT_EQ(plain.wait_exit(kFleetTimeoutMs), 1) << "an unauthenticated Fast DDS reader got:\n"
                                                 << plain.output();
  EXPECT_EQ(plain.output().find("sample "), std::string::npos) << plain.output();
}

}  // namespace
}  // namespace ceilpose
