// Interoperability with another vendor: eProsima Fast DDS (Debian's
// libfastrtps), decoding by hand the way rmw_fastrtps does, subscribes to a
// pose published by ceilpose over Cyclone in another process.
#include <gtest/gtest.h>

#include <string>

#include "tests/ipc/dds/dds_test_env.h"
#include "tests/support/child_process.h"

namespace ceilpose {
namespace {

using test::ChildProcess;

constexpr int64_t kTimeoutMs = 20'000;

TEST(DdsInterop, FastDdsSubscriberDecodesPublishedPose) {
#ifndef CEILPOSE_FASTDDS_LISTENER
  GTEST_SKIP() << "Fast DDS (libfastrtps-dev) not installed: run scripts/setup and reconfigure";
#else
  test::use_loopback_dds();
  const std::string domain = std::to_string(test::unique_domain_id());
  const std::string robot = test::unique_robot_name("fast");
  ChildProcess publisher({CEILPOSE_DDS_FAKE_ROBOT, "--robot", robot, "--domain", domain, "--x",
                          "1.25", "--y", "-0.5", "--yaw", "0.5", "--stamp-ns",
                          "1700000000123456789", "--rate", "50", "--duration", "60"});
  ASSERT_NE(publisher.read_until("ready", kTimeoutMs).find("ready"), std::string::npos);

  ChildProcess subscriber({CEILPOSE_FASTDDS_LISTENER, "--domain", domain, "--topic",
                           "rt/" + robot + "/pose", "--count", "3", "--timeout-ms", "15000"});
  const int rc = subscriber.wait_exit(kTimeoutMs);

  ASSERT_EQ(rc, 0) << "Fast DDS subscriber output:\n" << subscriber.output();
  const std::string& out = subscriber.output();
  const size_t first = out.find("sample ");
  ASSERT_NE(first, std::string::npos) << out;
  const std::string line = out.substr(first, out.find('\n', first) - first);
  EXPECT_NE(line.find("type=geometry_msgs::msg::dds_::PoseWithCovarianceStamped_"),
            std::string::npos)
      << line;
  EXPECT_NE(line.find("sec=1700000000 nanosec=123456789 frame=map"), std::string::npos) << line;
  EXPECT_NE(line.find("x=1.25 y=-0.5 z=0 "), std::string::npos) << line;
  // sin(0.25) and cos(0.25) to 9 significant digits.
  EXPECT_NE(line.find("qx=0 qy=0 qz=0.247403959 qw=0.968912422"), std::string::npos) << line;
  EXPECT_NE(line.find("cxx=0.0001 cxy=1e-05 cyy=0.0002 cyawyaw=0.003 czz=1000000"),
            std::string::npos)
      << line;
#endif
}

}  // namespace
}  // namespace ceilpose
