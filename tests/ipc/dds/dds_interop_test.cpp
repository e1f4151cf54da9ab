// Interoperability with another vendor: eProsima Fast DDS (Debian's
// libfastrtps), decoding by hand the way rmw_fastrtps does, subscribes to a
// pose published by ceilpose over Cyclone in another process.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "tests/ipc/dds/dds_test_env.h"
#include "tests/support/child_process.h"

namespace ceilpose {
namespace {

using test::ChildProcess;

constexpr int64_t kTimeoutMs = 20'000;

// The fake robot at (1.25, -0.5, 0.5 rad) with a fixed stamp, plus `extra`.
std::vector<std::string> fake_robot(const std::string& robot, const std::string& domain,
                                    const std::vector<std::string>& extra) {
  std::vector<std::string> args{CEILPOSE_DDS_FAKE_ROBOT, "--robot", robot, "--domain", domain};
  for (const char* a : {"--x", "1.25", "--y", "-0.5", "--yaw", "0.5", "--stamp-ns",
                        "1700000000123456789", "--rate", "50", "--duration", "60"})
    args.emplace_back(a);
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

TEST(DdsInterop, FastDdsSubscriberDecodesPublishedPose) {
  test::use_loopback_dds();
  const std::string domain = std::to_string(test::unique_domain_id());
  const std::string robot = test::unique_robot_name("fast");
  ChildProcess publisher(fake_robot(robot, domain, {}));
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
}

// "%.9g" of v: the listener prints every number so.
std::string g9(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

// Issue 13: nav_msgs/Odometry on rt/<robot>/odom, every field decoded by
// another vendor: header, child frame, the pose, and the twist in base_link
// (REP-105) with its covariance rotated there.
TEST(DdsInterop, FastDdsSubscriberDecodesPublishedOdometry) {
  test::use_loopback_dds();
  const std::string domain = std::to_string(test::unique_domain_id());
  const std::string robot = test::unique_robot_name("odom");
  ChildProcess publisher(fake_robot(robot, domain, {"--velocity", "0.5", "0.2", "0.3"}));
  ASSERT_NE(publisher.read_until("ready", kTimeoutMs).find("ready"), std::string::npos);

  ChildProcess subscriber({CEILPOSE_FASTDDS_LISTENER, "--domain", domain, "--topic",
                           "rt/" + robot + "/odom", "--type", "odom", "--count", "3",
                           "--timeout-ms", "15000"});
  const int rc = subscriber.wait_exit(kTimeoutMs);
  ASSERT_EQ(rc, 0) << "Fast DDS subscriber output:\n" << subscriber.output();
  const std::string& out = subscriber.output();
  const size_t first = out.find("sample ");
  ASSERT_NE(first, std::string::npos) << out;
  const std::string pose_line = out.substr(first, out.find('\n', first) - first);
  EXPECT_NE(pose_line.find("type=nav_msgs::msg::dds_::Odometry_"), std::string::npos) << pose_line;
  EXPECT_NE(pose_line.find("sec=1700000000 nanosec=123456789 frame=map"), std::string::npos)
      << pose_line;
  EXPECT_NE(pose_line.find("x=1.25 y=-0.5 z=0 qx=0 qy=0 qz=0.247403959 qw=0.968912422"),
            std::string::npos)
      << pose_line;
  EXPECT_NE(pose_line.find("cxx=0.0001 cxy=1e-05 cyy=0.0002 cyawyaw=0.003 czz=1000000"),
            std::string::npos)
      << pose_line;
  const size_t odom = out.find("odom ", first);
  ASSERT_NE(odom, std::string::npos) << out;
  const std::string line = out.substr(odom, out.find('\n', odom) - odom);
  // The world velocity (0.5, 0.2) m/s seen from a robot heading 0.5 rad.
  const double c = std::cos(0.5), s = std::sin(0.5);
  const std::string twist = "odom child=base_link vx=" + g9(0.5 * c + 0.2 * s) +
                            " vy=" + g9(-0.5 * s + 0.2 * c) + " vz=0 wx=0 wy=0 wz=0.3";
  EXPECT_NE(line.find(twist), std::string::npos) << line << "\nexpected " << twist;
  const std::string cov = "tvxvx=" + g9(c * c * 4e-4 + s * s * 1e-4) +
                          " tvxvy=" + g9(c * s * (1e-4 - 4e-4)) +
                          " tvyvy=" + g9(s * s * 4e-4 + c * c * 1e-4) +
                          " twzwz=0.0009 tvxwz=0 tvzvz=1000000 twxwx=1000000";
  EXPECT_NE(line.find(cov), std::string::npos) << line << "\nexpected " << cov;
}

// Issue 26: RViz without glue. Every pose as tf2_msgs/TFMessage on rt/tf,
// map -> <robot>/base_link, every field decoded by another vendor.
TEST(DdsInterop, FastDdsSubscriberDecodesTheTransformOfEveryPose) {
  test::use_loopback_dds();
  const std::string domain = std::to_string(test::unique_domain_id());
  const std::string robot = test::unique_robot_name("tf");
  ChildProcess publisher(fake_robot(robot, domain, {}));
  ASSERT_NE(publisher.read_until("ready", kTimeoutMs).find("ready"), std::string::npos);
  ChildProcess subscriber({CEILPOSE_FASTDDS_LISTENER, "--domain", domain, "--topic", "rt/tf",
                           "--type", "tf", "--count", "2", "--timeout-ms", "15000"});
  ASSERT_EQ(subscriber.wait_exit(kTimeoutMs), 0) << subscriber.output();
  const std::string& out = subscriber.output();
  const std::string expected =
      "tf transforms=1 | sec=1700000000 nanosec=123456789 parent=map "
      "child=" +
      robot +
      "/base_link x=1.25 y=-0.5 z=0 qx=0 qy=0 "
      "qz=0.247403959 qw=0.968912422";
  EXPECT_NE(out.find(expected), std::string::npos) << out << "\nexpected " << expected;
}

// The ceiling as visualization_msgs/MarkerArray on rt/<robot>/ceiling,
// published once at start and transient local: a viewer that starts later
// still gets it. The nominal 8 x 8 grid of the default layout: a DELETEALL,
// the red and the green rectangles as two CUBE_LISTs of 64, then 64 labels.
TEST(DdsInterop, ALateFastDdsViewerGetsTheCeilingWithEveryField) {
  test::use_loopback_dds();
  const std::string domain = std::to_string(test::unique_domain_id());
  const std::string robot = test::unique_robot_name("ceil");
  ChildProcess publisher(fake_robot(robot, domain, {}));
  ASSERT_NE(publisher.read_until("ready", kTimeoutMs).find("ready"), std::string::npos);
  ChildProcess subscriber({CEILPOSE_FASTDDS_LISTENER, "--domain", domain, "--topic",
                           "rt/" + robot + "/ceiling", "--type", "markers", "--count", "1",
                           "--timeout-ms", "15000"});
  ASSERT_EQ(subscriber.wait_exit(kTimeoutMs), 0) << subscriber.output();
  const std::string& out = subscriber.output();
  EXPECT_NE(out.find("markers count=67 | "), std::string::npos) << out;
  EXPECT_NE(out.find("ns= id=0 type=0 action=3 "), std::string::npos) << out.substr(0, 2000);
  EXPECT_NE(out.find("frame=map"), std::string::npos);
  // Red rectangles: 5 x 12 in at marker centre + 2.5 in east, on the 2.4384 m ceiling.
  EXPECT_NE(out.find("ns=ceiling id=0 type=6 action=0 x=0 y=0 z=0 qw=1 scale=0.127,0.3048,0.002 "
                     "rgba=0.784,0.118,0.157,1 lifetime=0 frame_locked=0 points=64 "
                     "first=0.0635,0,2.4384 colors=0 texture= uv=0 text= mesh= embedded=0"),
            std::string::npos)
      << out.substr(0, 2000);
  EXPECT_NE(out.find("ns=ceiling id=1 type=6 action=0"), std::string::npos);
  EXPECT_NE(out.find("points=64 first=-0.0635,0,2.4384"), std::string::npos) << "green";
  EXPECT_NE(out.find("ns=ceiling_codes id=63 type=9 action=0 x=4.2672 y=4.2672 z=2.3884"),
            std::string::npos)
      << "the last label, under marker (7, 7)";
  EXPECT_NE(out.find("text=7,7 "), std::string::npos);
}

}  // namespace
}  // namespace ceilpose
