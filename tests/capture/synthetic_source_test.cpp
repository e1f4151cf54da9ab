// SyntheticSource: a live camera over a FrameGenerator, here the simulator
// (sim::TrajectoryCamera, as ceilposed wires it).
#include "capture/synthetic_source.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "sim/camera_format.h"
#include "sim/trajectory.h"
#include "sim/trajectory_camera.h"

namespace ceilpose::capture {
namespace {

// A small camera keeps rendering well under the frame period on a loaded machine.
sim::TrajectoryCameraOptions small_scene() {
  sim::TrajectoryCameraOptions o;
  o.scene.intrinsics.width = 160;
  o.scene.intrinsics.height = 120;
  o.scene.intrinsics.fx = o.scene.intrinsics.fy = 132.5;
  o.scene.intrinsics.cx = 79.5;
  o.scene.intrinsics.cy = 59.5;
  o.trajectory_start_s = 3.0;
  return o;
}

SourceOptions at_rate(double fps) {
  SourceOptions o;
  o.fps = fps;
  return o;
}

std::shared_ptr<FrameGenerator> small_camera() {
  return std::make_shared<sim::TrajectoryCamera>(small_scene());
}

// The next frame within 100 polls of 100 ms; false if none came.
bool wait_frame(SyntheticSource& source, Frame* f) {
  for (int calls = 0; calls < 100; ++calls)
    if (source.next(f, 100) == NextStatus::kFrame) return true;
  return false;
}

// Proves capture needs nothing of the simulator: a generator that only
// stamps what it was asked.
struct StampingGenerator final : FrameGenerator {
  const CameraIntrinsics& intrinsics() const override { return k; }
  void generate(int64_t elapsed_ns, uint64_t tick, Image* out, Pose2D* truth) override {
    out->data()[0] = static_cast<uint8_t>(tick);
    *truth = Pose2D{static_cast<double>(elapsed_ns) * 1e-9, static_cast<double>(tick), 0.0};
  }
  std::string describe() const override { return "stamps"; }
  CameraIntrinsics k = [] {
    CameraIntrinsics c;
    c.width = 8;
    c.height = 6;
    return c;
  }();
};

TEST(SyntheticSource, AnyGeneratorFeedsItAndItsTicksAndTimesArriveWithTheFrames) {
  auto generator = std::make_shared<StampingGenerator>();
  SyntheticSource source(at_rate(200.0), generator);
  ASSERT_TRUE(source.open());
  ASSERT_TRUE(source.start());
  EXPECT_NE(source.describe().find("8x6 RGB24 200.0 fps, stamps"), std::string::npos)
      << source.describe();
  Frame first;
  for (int i = 0; i < 3; ++i) {
    Frame f;
    int calls = 0;
    NextStatus s;
    while ((s = source.next(&f, 100)) == NextStatus::kTimeout) ASSERT_LT(++calls, 100);
    ASSERT_EQ(s, NextStatus::kFrame);
    if (i == 0) first = f;
    EXPECT_EQ(f.image.width, 8);
    EXPECT_EQ(f.image.data[0], static_cast<uint8_t>(f.ground_truth.y_m));
    EXPECT_NEAR(f.ground_truth.x_m - first.ground_truth.x_m,
                (f.capture_ns - first.capture_ns) * 1e-9, 1e-9);
    source.release(f);
  }
}

TEST(MakeFrameSource, SyntheticWithoutAGeneratorIsAnErrorNamingTheSpec) {
  auto r = make_frame_source("synthetic", SourceOptions{});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("synthetic"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("generator"), std::string::npos) << r.error().message;
}

TEST(SyntheticSource, DeliversRenderedFramesWithTheirTrajectoryGroundTruth) {
  const sim::TrajectoryCameraOptions o = small_scene();
  SyntheticSource source(at_rate(50.0), std::make_shared<sim::TrajectoryCamera>(o));
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
    const Pose2D expected = sim::trajectory_pose(o.scene.layout, t_s);
    EXPECT_NEAR(f.ground_truth.x_m, expected.x_m, 1e-9);
    EXPECT_NEAR(f.ground_truth.y_m, expected.y_m, 1e-9);
    EXPECT_NEAR(f.ground_truth.yaw_rad, expected.yaw_rad, 1e-9);
    EXPECT_LE(f.capture_ns, f.dequeue_ns);
    source.release(f);
  }
}

TEST(SyntheticSource, FramesFollowTheConfiguredRateOnTheMonotonicClock) {
  SyntheticSource source(at_rate(100.0), small_camera());
  ASSERT_TRUE(source.open());
  ASSERT_TRUE(source.start());
  int64_t previous_ns = 0;
  for (int i = 0; i < 6; ++i) {
    Frame f;
    ASSERT_TRUE(wait_frame(source, &f));
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

// Rendering slower than the frame rate: ticks that pass during a render are
// lost, as a camera loses them, and the next exposure is the next tick after
// the render ended (25 ms at 100 fps: 30 ms later), never a passed one.
struct SlowGenerator final : FrameGenerator {
  const CameraIntrinsics& intrinsics() const override { return stamping.k; }
  void generate(int64_t elapsed_ns, uint64_t tick, Image* out, Pose2D* truth) override {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));  // 2.5 periods at 100 fps
    stamping.generate(elapsed_ns, tick, out, truth);
  }
  std::string describe() const override { return "slow"; }
  StampingGenerator stamping;
};

TEST(SyntheticSource, RenderingSlowerThanTheRateWaitsForTheNextTickNotAPassedOne) {
  SyntheticSource source(at_rate(100.0), std::make_shared<SlowGenerator>());
  ASSERT_TRUE(source.open());
  ASSERT_TRUE(source.start());
  int64_t previous_ns = 0;
  for (int i = 0; i < 5; ++i) {
    Frame f;
    ASSERT_TRUE(wait_frame(source, &f));
    if (i > 0) {
      const int64_t gap_ns = f.capture_ns - previous_ns;
      EXPECT_GE(gap_ns, 30'000'000) << "frame " << i << " exposed during the previous render";
      EXPECT_EQ(gap_ns % 10'000'000, 0) << gap_ns;
    }
    EXPECT_GE(f.dequeue_ns, f.capture_ns + 25'000'000) << "handed over before it was rendered";
    previous_ns = f.capture_ns;
    source.release(f);
  }
  EXPECT_GE(source.stats().drops, 8u);  // >= 2 ticks lost per frame after the first
}

TEST(SyntheticSource, TheImageShowsTheCeilingNotABlank) {
  SyntheticSource source(at_rate(50.0), small_camera());
  ASSERT_TRUE(source.open());
  ASSERT_TRUE(source.start());
  Frame f;
  ASSERT_TRUE(wait_frame(source, &f));
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
  SyntheticSource source(at_rate(0.0), small_camera());
  auto r = source.open();
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("frame rate"), std::string::npos) << r.error().message;
}

// A synthetic USB camera (issue 29): frames handed over in YUYV, converted
// from the same render as a camera's ISP would (sim/camera_format.h), so
// latency_bench and the daemon's path see the camera's own format.
TEST(SyntheticSource, AYuyvCameraHandsOverTheSameSceneInYuyv) {
  sim::TrajectoryCameraOptions o = small_scene();
  sim::TrajectoryCamera rgb_camera(o);
  o.format = PixelFormat::kYuyv;
  auto yuyv_camera = std::make_shared<sim::TrajectoryCamera>(o);
  EXPECT_EQ(yuyv_camera->format(), PixelFormat::kYuyv);
  Image rgb(160, 120, PixelFormat::kRgb24), yuyv(160, 120, PixelFormat::kYuyv);
  Pose2D a, b;
  rgb_camera.generate(0, 0, &rgb, &a);
  yuyv_camera->generate(0, 0, &yuyv, &b);
  const Image expected = sim::convert_rgb(rgb, PixelFormat::kYuyv);
  ASSERT_EQ(yuyv.stride_bytes(), 2 * 160);
  EXPECT_EQ(std::memcmp(yuyv.data(), expected.data(), 2 * 160 * 120), 0);

  SyntheticSource source(at_rate(200.0), yuyv_camera);
  ASSERT_TRUE(source.open());
  ASSERT_TRUE(source.start());
  Frame f;
  ASSERT_TRUE(wait_frame(source, &f));
  EXPECT_EQ(f.image.format, PixelFormat::kYuyv);
  EXPECT_EQ(f.image.stride_bytes, 2 * 160);
  source.release(f);
  source.stop();
}

}  // namespace
}  // namespace ceilpose::capture
