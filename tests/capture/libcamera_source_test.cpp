// LibcameraSource on a machine without a camera: open() fails cleanly and says so.
#include "capture/libcamera_source.h"

#include <gtest/gtest.h>
#include <libcamera/camera_manager.h>

namespace ceilpose::capture {
namespace {

bool machine_has_a_camera() {
  libcamera::CameraManager manager;
  if (manager.start() < 0) return false;
  const bool any = !manager.cameras().empty();
  manager.stop();
  return any;
}

TEST(LibcameraSource, WithNoCameraOpenFailsSayingSo) {
  if (machine_has_a_camera()) GTEST_SKIP() << "a camera is connected; this test needs none";
  auto made = make_frame_source("libcamera", SourceOptions{});
  ASSERT_TRUE(made) << made.error().message;
  auto r = (*made)->open();
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("no camera"), std::string::npos) << r.error().message;
  // The source stays Closed and can be destroyed or retried.
  Frame f;
  EXPECT_EQ((*made)->next(&f, 1), NextStatus::kError);
}

TEST(LibcameraSource, AnUnknownCameraIdFailsNamingIt) {
  LibcameraSource source("no-such-camera-id", SourceOptions{});
  auto r = source.open();
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("no-such-camera-id"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace ceilpose::capture
