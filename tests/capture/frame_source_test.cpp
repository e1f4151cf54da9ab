// make_frame_source: the SPEC §7 source spec.
#include "capture/frame_source.h"

#include <gtest/gtest.h>

#include "sim/trajectory_camera.h"

namespace ceilpose::capture {
namespace {

TEST(MakeFrameSource, AnUnknownSpecIsRejectedListingTheValidForms) {
  auto r = make_frame_source("webcam", SourceOptions{});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("'webcam'"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("v4l2:/dev/videoN"), std::string::npos) << r.error().message;
}

TEST(MakeFrameSource, ReplayWithoutADirectoryIsRejected) {
  auto r = make_frame_source("replay:", SourceOptions{});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("directory"), std::string::npos) << r.error().message;
}

TEST(MakeFrameSource, V4l2SpecNamesTheDeviceNode) {
  auto r = make_frame_source("v4l2:/dev/video3", SourceOptions{});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_NE((*r)->describe().find("/dev/video3"), std::string::npos) << (*r)->describe();
}

TEST(MakeFrameSource, AMissingV4l2DeviceFailsInOpenNamingIt) {
  auto r = make_frame_source("v4l2:/dev/ceilpose-no-such-video", SourceOptions{});
  ASSERT_TRUE(r) << r.error().message;
  auto opened = (*r)->open();
  ASSERT_FALSE(opened);
  EXPECT_NE(opened.error().message.find("/dev/ceilpose-no-such-video"), std::string::npos)
      << opened.error().message;
}

TEST(MakeFrameSource, SyntheticSpecMakesALiveSyntheticCameraOverItsGenerator) {
  auto r =
      make_frame_source("synthetic", SourceOptions{},
                        std::make_shared<sim::TrajectoryCamera>(sim::TrajectoryCameraOptions{}));
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_NE((*r)->describe().find("synthetic 640x480"), std::string::npos) << (*r)->describe();
  EXPECT_TRUE((*r)->live());
}

}  // namespace
}  // namespace ceilpose::capture
