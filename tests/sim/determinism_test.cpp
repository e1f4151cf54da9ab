// Frames are a function of (scene seed, frame seed), and rendering into the
// same image does not allocate again.
#include <gtest/gtest.h>

#include <cstring>

#include "sim/renderer.h"
#include "sim/scenarios.h"
#include "tests/sim/sim_test_support.h"

namespace ceilpose::sim {
namespace {

Effects everything() { return testing::every_effect(70); }

bool same_pixels(const Image& a, const Image& b) {
  return a.size_bytes() == b.size_bytes() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
}

TEST(RendererDeterminism, SameSeedsGiveIdenticalFramesWithEveryEffect) {
  SceneOptions options;
  options.seed = 42;
  Renderer r1(options), r2(options);
  Image a, b;
  r1.render({1.2, 2.3, 0.7}, CameraMount{}, everything(), 9, &a);
  r2.render({1.2, 2.3, 0.7}, CameraMount{}, everything(), 9, &b);
  EXPECT_TRUE(same_pixels(a, b));
}

TEST(RendererDeterminism, AnotherFrameSeedGivesAnotherFrame) {
  SceneOptions options;
  Renderer r(options);
  Image a, b;
  r.render({1.2, 2.3, 0.7}, CameraMount{}, everything(), 9, &a);
  r.render({1.2, 2.3, 0.7}, CameraMount{}, everything(), 10, &b);
  EXPECT_FALSE(same_pixels(a, b));
}

TEST(RendererDeterminism, AnotherSceneSeedGivesAnotherFrame) {
  SceneOptions o1, o2;
  o2.seed = o1.seed + 1;
  Renderer r1(o1), r2(o2);
  Image a, b;
  // Without noise: the difference can only come from the scene (clutter).
  Effects e;
  e.clutter_objects = kMaxClutterObjects;
  for (int k = 0; k < 8; ++k) {
    const Pose2D p{0.6 * k, 0.5 * k, 0.3 * k};
    r1.render(p, CameraMount{}, e, 1, &a);
    r2.render(p, CameraMount{}, e, 1, &b);
    if (!same_pixels(a, b)) return;
  }
  ADD_FAILURE() << "eight views of two scenes with different seeds were identical";
}

TEST(RendererDeterminism, OutputHasTheIntrinsicsSizeAndFormat) {
  SceneOptions options;
  options.intrinsics.width = 320;
  options.intrinsics.height = 200;
  options.intrinsics.cx = 159.5;
  options.intrinsics.cy = 99.5;
  Renderer r(options);
  Image img;
  r.render({1.0, 1.0, 0.0}, CameraMount{}, Effects{}, 1, &img);
  EXPECT_EQ(img.width(), 320);
  EXPECT_EQ(img.height(), 200);
  EXPECT_EQ(img.format(), PixelFormat::kRgb24);
}

TEST(RendererDeterminism, RenderingAgainReusesTheOutputBuffer) {
  SceneOptions options;
  Renderer r(options);
  Image img;
  r.render({1.0, 1.0, 0.0}, CameraMount{}, everything(), 1, &img);
  const uint8_t* first = img.data();
  r.render({2.0, 1.5, 1.0}, CameraMount{}, everything(), 2, &img);
  EXPECT_EQ(img.data(), first);
}

}  // namespace
}  // namespace ceilpose::sim
