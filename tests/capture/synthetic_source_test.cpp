// SyntheticSource: the simulator as a live camera.
#include "capture/synthetic_source.h"

#include <gtest/gtest.h>

#include "sim/trajectory.h"

namespace ceilpose::capture {
namespace {

// A small camera keeps rendering well under the frame period on a loaded machine.
SourceOptions small_camera(double fps) {
  SourceOptions o;
  o.fps = fps;
  o.intrinsics.width = 160;
  o.intrinsics.height = 120;
  o.intrinsics.fx = o.intrinsics.fy = 132.5;
  o.intrinsics.cx = 79.5;
  o.intrinsics.cy = 59.5;
  o.trajectory_start_s = 3.0;
  return o;
}

TEST(SyntheticSource, DeliversRenderedFramesWithTheirTrajectoryGroundTruth) {
  SourceOptions o = small_camera(50.0);
  SyntheticSource source(o);
  ASSERT_TRUE(source.open());
  ASSERT_TRUE(source.start());
  Frame first;
  for (int i = 0; i < 5; ++i) {
    Frame f;
    NextStatus s;
    int calls = 0;
    while ((s = source.next(&f, 100)) == NextStatus::kTimeout) ASSERT_LT(++calls, 100);
    ASSERT_EQ(s, NextStatus::kFrame);
    if (i == 0) first = f;
    ASSERT_TRUE(f.has_ground_truth);
    EXPECT_EQ(f.image.width, 160);
    EXPECT_EQ(f.image.height, 120);
    EXPECT_EQ(f.image.format, PixelFormat::kRgb24);
    const double t_s = o.trajectory_start_s + (f.capture_ns - first.capture_ns) * 1e-9;
    const Pose2D expected = sim::trajectory_pose(o.layout, t_s);
    EXPECT_NEAR(f.ground_truth.x_m, expected.x_m, 1e-9);
    EXPECT_NEAR(f.ground_truth.y_m, expected.y_m, 1e-9);
    EXPECT_NEAR(f.ground_truth.yaw_rad, expected.yaw_rad, 1e-9);
    EXPECT_LE(f.capture_ns, f.dequeue_ns);
    source.release(f);
  }
}

TEST(SyntheticSource, FramesFollowTheConfiguredRateOnTheMonotonicClock) {
  SyntheticSource source(small_camera(100.0));
  ASSERT_TRUE(source.open());
  ASSERT_TRUE(source.start());
  int64_t previous_ns = 0;
  for (int i = 0; i < 6; ++i) {
    Frame f;
    int calls = 0;
    while (source.next(&f, 100) != NextStatus::kFrame) ASSERT_LT(++calls, 100);
    if (i > 0) {
      // Capture times sit on the 10 ms grid; a loaded machine may skip ticks
      // (counted as drops) but never moves a frame off the grid.
      const int64_t gap_ns = f.capture_ns - previous_ns;
      EXPECT_EQ(gap_ns % 10'000'000, 0) << gap_ns;
      EXPECT_GE(gap_ns, 10'000'000);
    }
    previous_ns = f.capture_ns;
    source.release(f);
  }
}

TEST(SyntheticSource, TheImageShowsTheCeilingNotABlank) {
  SyntheticSource source(small_camera(50.0));
  ASSERT_TRUE(source.open());
  ASSERT_TRUE(source.start());
  Frame f;
  int calls = 0;
  while (source.next(&f, 100) != NextStatus::kFrame) ASSERT_LT(++calls, 100);
  int lo = 255;
  int hi = 0;
  for (int y = 0; y < f.image.height; ++y) {
    for (int x = 0; x < f.image.width * 3; ++x) {
      lo = std::min<int>(lo, f.image.row(y)[x]);
      hi = std::max<int>(hi, f.image.row(y)[x]);
    }
  }
  EXPECT_GT(hi - lo, 100) << "markers and tiles must give contrast";
}

TEST(SyntheticSource, ANonPositiveFrameRateFailsInOpen) {
  SyntheticSource source(small_camera(0.0));
  auto r = source.open();
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("frame rate"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace ceilpose::capture
