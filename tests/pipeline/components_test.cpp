#include "pipeline/components.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <vector>

#include "core/pixel_read.h"
#include "tests/pipeline/detect_scene_support.h"

namespace ceilpose {
namespace {

constexpr Rgb kRed{200, 30, 40};
constexpr Rgb kGreen{40, 160, 70};
constexpr Rgb kDot{25, 25, 25};

// The same components, each the same: class, area, dark pixels, centroid.
void expect_same_components(std::span<const Component> got, std::span<const Component> want) {
  ASSERT_GE(want.size(), 3u);
  ASSERT_EQ(got.size(), want.size());
  for (size_t k = 0; k < want.size(); ++k) {
    EXPECT_EQ(got[k].cls, want[k].cls) << k;
    EXPECT_EQ(got[k].area_px, want[k].area_px) << k;
    EXPECT_EQ(got[k].dark_px, want[k].dark_px) << k;
    EXPECT_DOUBLE_EQ(got[k].cx, want[k].cx) << k;
    EXPECT_DOUBLE_EQ(got[k].cy, want[k].cy) << k;
  }
}

class ComponentsTest : public ::testing::Test {
 protected:
  static constexpr int kWidth = 120;
  static constexpr int kHeight = 90;
  ComponentsTest() : frame(kWidth, kHeight, PixelFormat::kRgb24) {
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) test::put_rgb(&frame, x, y, layout.tile);
  }
  void fill(int x0, int y0, int x1, int y1, Rgb c) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) test::put_rgb(&frame, x, y, c);
  }
  std::span<const Component> label() {
    EXPECT_TRUE(labeler.label(frame.view(), classifier));
    return labeler.components();
  }

  CeilingLayout layout;
  DetectorParams params;
  ColorClassifier classifier{params, layout.tile};
  ComponentLabeler labeler{kWidth, kHeight, params};
  Image frame;
};

TEST_F(ComponentsTest, FilledRectangleHasExactAreaCentroidAndMoments) {
  fill(10, 20, 29, 59, kRed);  // 20 x 40
  const auto comps = label();
  ASSERT_EQ(comps.size(), 1u);
  const Component& c = comps[0];
  EXPECT_EQ(c.cls, PixelClass::kRed);
  EXPECT_EQ(c.area_px, 800);
  EXPECT_DOUBLE_EQ(c.cx, 19.5);
  EXPECT_DOUBLE_EQ(c.cy, 39.5);
  // Discrete variance of n consecutive integers: (n² − 1) / 12.
  EXPECT_NEAR(c.mu20, (20.0 * 20.0 - 1.0) / 12.0, 1e-9);
  EXPECT_NEAR(c.mu02, (40.0 * 40.0 - 1.0) / 12.0, 1e-9);
  EXPECT_NEAR(c.mu11, 0.0, 1e-9);
  EXPECT_EQ(c.x_min, 10);
  EXPECT_EQ(c.y_max, 59);
  EXPECT_FALSE(c.touches_border);
}

TEST_F(ComponentsTest, DiagonalNeighboursAreOneComponent) {
  fill(10, 10, 10, 10, kGreen);
  fill(11, 11, 11, 11, kGreen);
  fill(10, 12, 10, 12, kGreen);
  const auto comps = label();
  ASSERT_EQ(comps.size(), 1u);
  EXPECT_EQ(comps[0].area_px, 3);
}

TEST_F(ComponentsTest, UShapeJoinsThroughItsBottom) {
  // The two arms are separate components until the bottom row joins them:
  // union-find must merge labels already given.
  fill(10, 10, 14, 40, kRed);
  fill(30, 10, 34, 40, kRed);
  fill(10, 41, 34, 45, kRed);
  const auto comps = label();
  ASSERT_EQ(comps.size(), 1u);
  EXPECT_EQ(comps[0].area_px, 2 * 5 * 31 + 25 * 5);
}

TEST_F(ComponentsTest, TouchingRedAndGreenStaySeparate) {
  fill(10, 10, 29, 49, kRed);
  fill(30, 10, 49, 49, kGreen);
  const auto comps = label();
  ASSERT_EQ(comps.size(), 2u);
  EXPECT_NE(comps[0].cls, comps[1].cls);
  EXPECT_EQ(comps[0].area_px, 800);
  EXPECT_EQ(comps[1].area_px, 800);
}

TEST_F(ComponentsTest, EnclosedDotCountsTowardsItsRectangle) {
  fill(10, 20, 29, 59, kRed);
  fill(15, 30, 24, 34, kDot);  // inside, margins on every side
  const auto comps = label();
  ASSERT_EQ(comps.size(), 1u);
  EXPECT_EQ(comps[0].area_px, 800);
  EXPECT_EQ(comps[0].dark_px, 50);
  EXPECT_DOUBLE_EQ(comps[0].cx, 19.5);
  EXPECT_DOUBLE_EQ(comps[0].cy, 39.5);
}

TEST_F(ComponentsTest, DarkBlobBesideARectangleIsNotPartOfIt) {
  fill(10, 20, 29, 59, kRed);
  fill(30, 30, 39, 34, kDot);  // touches the rectangle on its left side only
  const auto comps = label();
  ASSERT_EQ(comps.size(), 1u);
  EXPECT_EQ(comps[0].area_px, 800);
  EXPECT_EQ(comps[0].dark_px, 0);
}

TEST_F(ComponentsTest, BorderContactIsFlagged) {
  fill(0, 20, 9, 29, kRed);
  const auto comps = label();
  ASSERT_EQ(comps.size(), 1u);
  EXPECT_TRUE(comps[0].touches_border);
}

TEST_F(ComponentsTest, RotatedRectangleGivesItsOrientation) {
  // Orientation from tan 2θ = 2 mu11 / (mu20 − mu02), image axes.
  for (double deg : {-60.0, -20.0, 0.0, 25.0, 45.0, 80.0}) {
    const double a = deg * std::numbers::pi / 180.0;
    const double ca = std::cos(a), sa = std::sin(a);
    fill(0, 0, kWidth - 1, kHeight - 1, layout.tile);
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        const double dx = x - 60.0, dy = y - 45.0;
        if (std::abs(ca * dx + sa * dy) <= 30.0 && std::abs(-sa * dx + ca * dy) <= 8.0)
          test::put_rgb(&frame, x, y, kGreen);
      }
    }
    const auto comps = label();
    ASSERT_EQ(comps.size(), 1u) << deg;
    EXPECT_NEAR(comps[0].orientation_rad(), a, 0.01) << deg;
  }
}

TEST_F(ComponentsTest, GreyFrameHasNoComponents) {
  fill(10, 20, 29, 59, kRed);
  const Image grey = test::convert_rgb(frame, PixelFormat::kGray8);
  EXPECT_TRUE(labeler.label(grey.view(), classifier));
  EXPECT_TRUE(labeler.components().empty());
}

TEST_F(ComponentsTest, NoiseBeyondTheRunBudgetAbandonsTheFrame) {
  std::mt19937 rng(3);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) test::put_rgb(&frame, x, y, (rng() & 1) ? kRed : kGreen);
  EXPECT_FALSE(labeler.label(frame.view(), classifier));
  EXPECT_TRUE(labeler.components().empty());
}

// The BT.601 levels the detector must give pixel (x, y) of a YUV frame,
// written out pixel by pixel: chroma 3:1 with the neighbouring pair (and,
// 4:2:0, the neighbouring chroma row), kept at x16, then to 2^12-scaled
// ints and clamped. The sweep computes the same in vectorised stages.
Rgb reference_levels(const ImageView& f, int x, int y) {
  auto chroma4 = [&](int pair, int* u, int* v) {
    if (f.format == PixelFormat::kYuyv) {
      *u = 4 * f.row(y)[4 * pair + 1], *v = 4 * f.row(y)[4 * pair + 3];
      return;
    }
    const int yo = chroma_neighbour_row(y, f.height);
    const bool nv12 = f.format == PixelFormat::kNv12;
    const int un = nv12 ? f.uv_row(y)[2 * pair] : f.u_row(y)[pair];
    const int uf = nv12 ? f.uv_row(yo)[2 * pair] : f.u_row(yo)[pair];
    const int vn = nv12 ? f.uv_row(y)[2 * pair + 1] : f.v_row(y)[pair];
    const int vf = nv12 ? f.uv_row(yo)[2 * pair + 1] : f.v_row(yo)[pair];
    *u = 3 * un + uf, *v = 3 * vn + vf;
  };
  int u_own = 0, v_own = 0, u_nb = 0, v_nb = 0;
  chroma4(x / 2, &u_own, &v_own);
  chroma4(chroma_neighbour_pair(x, f.width), &u_nb, &v_nb);
  const int luma = f.format == PixelFormat::kYuyv ? f.row(y)[2 * x] : f.row(y)[x];
  const int c = 16 * (298 * (luma - 16) + 128);
  const int d = 3 * u_own + u_nb - 2048, e = 3 * v_own + v_nb - 2048;
  auto level = [](int v) { return static_cast<uint8_t>(std::clamp(v >> 12, 0, 255)); };
  return {level(c + 409 * e), level(c - 100 * d - 208 * e), level(c + 516 * d)};
}

// Every pixel of a noisy YUV frame (saturated and clamped levels included)
// is classified as its reference levels are: the components of the YUV
// frame, swept whole and in windows on odd columns, equal those of the RGB
// frame made of the reference levels, to the last bit.
TEST_F(ComponentsTest, YuvFramesClassifyEveryPixelAsItsBt601LevelsDo) {
  fill(10, 20, 29, 59, kRed);
  fill(61, 11, 84, 40, kGreen);
  fill(66, 20, 71, 25, kDot);
  fill(100, 50, 119, 89, {255, 0, 0});  // saturated: the clamps
  // One pixel pair wide and one chroma row high: a neighbour's chroma takes
  // a quarter of theirs, enough to make a tile pixel green.
  fill(32, 2, 33, 40, {0, 255, 0});
  fill(88, 30, 118, 31, {0, 255, 0});
  // Strong noise on the lower half; above it a camera's read noise, which
  // leaves most tile pixels in the classifier's background box (skipped).
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> noise(-40, 40), read_noise(-2, 2);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      uint8_t* p = frame.row(y) + 3 * x;
      for (int k = 0; k < 3; ++k)
        p[k] = static_cast<uint8_t>(
            std::clamp(p[k] + (y >= kHeight / 2 ? noise(rng) : read_noise(rng)), 0, 255));
    }
  }
  for (PixelFormat format : {PixelFormat::kYuyv, PixelFormat::kNv12, PixelFormat::kYuv420}) {
    SCOPED_TRACE(to_string(format));
    const Image yuv = test::convert_rgb(frame, format);
    Image levels(kWidth, kHeight, PixelFormat::kRgb24);
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x)
        test::put_rgb(&levels, x, y, reference_levels(yuv.view(), x, y));
    if (format == PixelFormat::kYuyv) {
      int in_box = 0;
      for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; x += 2) {
          const uint8_t* q = yuv.view().row(y) + 2 * x;
          const YuvBox& box = classifier.background_yuv();
          in_box += 2 * (box.contains(q[0], q[1], q[3]) && box.contains(q[2], q[1], q[3]));
        }
      EXPECT_GT(in_box, kWidth * kHeight / 4) << "pixels whose pair is in the box";
    }
    const PixelWindow windows[] = {{3, 7, 37, 66}, {55, 5, 91, 45}, {95, 45, 119, 89}};
    for (bool windowed : {false, true}) {
      SCOPED_TRACE(windowed ? "windows" : "whole");
      auto sweep = [&](const Image& image) {
        const bool ok = windowed ? labeler.label(image.view(), classifier, windows)
                                 : labeler.label(image.view(), classifier);
        EXPECT_TRUE(ok);
        return std::vector<Component>(labeler.components().begin(), labeler.components().end());
      };
      const std::vector<Component> want = sweep(levels);
      expect_same_components(sweep(yuv), want);
    }
  }
}

// Every other pixel of every other row (or every 4th of every 4th, for
// large markers at 1280x960), given back in the frame's pixels: a 20 x 40
// rectangle keeps its area and its second moments exactly (+(s²-1)/12 px²
// restores the variance a lattice of step s does not hold), and its
// centroid to the (s-1)/2 px its sampling phase shifts it by, at every phase.
TEST_F(ComponentsTest, SampledSweepGivesAreaMomentsAndCentroidInTheFramesPixels) {
  for (int step : {2, 4}) {
    for (int x0 = 8; x0 < 8 + step; ++x0) {
      SCOPED_TRACE(testing::Message() << "step " << step << " x0 " << x0);
      fill(0, 0, kWidth - 1, kHeight - 1, layout.tile);
      fill(x0, 20, x0 + 19, 59, kRed);
      fill(x0 + 8, 36, x0 + 11, 41, kDot);  // a 4 x 6 dot, folded in
      ASSERT_TRUE(labeler.label_sampled(frame.view(), classifier, step));
      const auto comps = labeler.components();
      ASSERT_EQ(comps.size(), 1u);
      const Component& c = comps[0];
      EXPECT_EQ(c.cls, PixelClass::kRed);
      EXPECT_EQ(c.area_px, 800);
      EXPECT_EQ(c.dark_px, step == 2 ? 24 : 32);  // 2 x 3 or 1 x 2 samples
      EXPECT_NEAR(c.cx, x0 + 9.5, 0.5 * (step - 1) + 1e-9);
      EXPECT_NEAR(c.cy, 39.5, 0.5 * (step - 1) + 1e-9);
      EXPECT_NEAR(c.mu20, (20.0 * 20.0 - 1.0) / 12.0, 1e-9);
      EXPECT_NEAR(c.mu02, (40.0 * 40.0 - 1.0) / 12.0, 1e-9);
      EXPECT_NEAR(c.mu11, 0.0, 1e-9);
      EXPECT_FALSE(c.touches_border);
      EXPECT_EQ(labeler.swept_px(), ((kWidth + step - 1) / step) * ((kHeight + step - 1) / step));
    }
  }
  EXPECT_FALSE(labeler.label_sampled(frame.view(), classifier, 3)) << "steps are 2 or 4";
}

TEST_F(ComponentsTest, HalvedSweepFlagsTheLastSampledRowAndColumnAsBorder) {
  fill(100, 30, kWidth - 1, 50, kGreen);  // sampled up to column 118
  ASSERT_TRUE(labeler.label_sampled(frame.view(), classifier, 2));
  ASSERT_EQ(labeler.components().size(), 1u);
  EXPECT_TRUE(labeler.components()[0].touches_border);
  EXPECT_EQ(labeler.components()[0].x_max, kWidth - 1);
}

// A noise-free frame's rectangles in YUYV, NV12 and I420 give the RGB
// frame's halved components but for a sample where the chroma pair (4:2:0:
// also the chroma row) straddles a rectangle's edge: its own chroma, half
// the rectangle's, may take it in. A column or row of samples at most
// (here 60 and 96 px of the green's 720), the centroid a pixel.
TEST_F(ComponentsTest, HalvedSweepOfYuvFramesGivesTheRgbFramesRectangles) {
  fill(10, 20, 29, 59, kRed);
  fill(61, 11, 84, 40, kGreen);
  fill(66, 20, 71, 25, kDot);
  ASSERT_TRUE(labeler.label_sampled(frame.view(), classifier, 2));
  const std::vector<Component> want(labeler.components().begin(), labeler.components().end());
  ASSERT_EQ(want.size(), 2u);
  for (PixelFormat format : {PixelFormat::kYuyv, PixelFormat::kNv12, PixelFormat::kYuv420}) {
    SCOPED_TRACE(to_string(format));
    const Image yuv = test::convert_rgb(frame, format);
    ASSERT_TRUE(labeler.label_sampled(yuv.view(), classifier, 2));
    const auto got = labeler.components();
    ASSERT_EQ(got.size(), want.size());
    for (size_t k = 0; k < want.size(); ++k) {
      EXPECT_EQ(got[k].cls, want[k].cls) << k;
      EXPECT_NEAR(got[k].area_px, want[k].area_px, 0.15 * want[k].area_px) << k;
      EXPECT_NEAR(got[k].cx, want[k].cx, 1.0) << k;
      EXPECT_NEAR(got[k].cy, want[k].cy, 1.0) << k;
    }
  }
}

// A halved or quartered sweep of YUYV, NV12 and I420 classifies each sample
// exactly as its own BT.601 levels (its pair's or chroma row's chroma) do,
// whether or not the sample lies in the classifier's background box and is
// left unconverted: tile with a camera's read noise (in the box), noise
// that leaves it, markers, a dot and saturated colour, with and without a
// colour cast that the gains undo.
TEST_F(ComponentsTest, SampledYuvSweepClassifiesEachSampleAsItsOwnLevelsDo) {
  fill(10, 20, 29, 59, kRed);
  fill(61, 11, 84, 40, kGreen);
  fill(66, 20, 71, 25, kDot);
  fill(100, 50, 119, 89, {255, 0, 0});
  std::mt19937 rng(5);
  std::normal_distribution<double> read_noise(0.0, 2.0);
  std::uniform_int_distribution<int> wild(-60, 60);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      uint8_t* p = frame.row(y) + 3 * x;
      const bool noisy = y >= 70 && x < 50;  // a patch of strong noise
      for (int k = 0; k < 3; ++k) {
        const double n = noisy ? wild(rng) : read_noise(rng);
        p[k] = static_cast<uint8_t>(std::clamp(static_cast<int>(std::lround(p[k] + n)), 0, 255));
      }
    }
  }
  const Image plain = frame;
  for (const std::array<float, 3> cast :
       {std::array<float, 3>{1.0f, 1.0f, 1.0f}, std::array<float, 3>{0.85f, 1.05f, 1.2f}}) {
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth * 3; ++x)
        frame.row(y)[x] = static_cast<uint8_t>(
            std::min(255.0f, std::round(plain.view().row(y)[x] * cast[x % 3])));
    const std::array<float, 3> gains{1 / cast[0], 1 / cast[1], 1 / cast[2]};
    classifier.set_gains(gains);
    ASSERT_FALSE(classifier.background_yuv().empty());
    for (PixelFormat format : {PixelFormat::kYuyv, PixelFormat::kNv12, PixelFormat::kYuv420}) {
      const Image yuv = test::convert_rgb(frame, format);
      Image levels(kWidth, kHeight, PixelFormat::kRgb24);
      int in_box = 0;
      for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
          uint8_t r = 0, g = 0, b = 0;
          read_rgb(yuv.view(), x, y, &r, &g, &b);
          test::put_rgb(&levels, x, y, {r, g, b});
          const uint8_t* q = yuv.view().row(y);
          if (format == PixelFormat::kYuyv && x % 2 == 0)
            in_box += classifier.background_yuv().contains(q[2 * x], q[2 * x + 1], q[2 * x + 3]);
        }
      if (format == PixelFormat::kYuyv) {
        EXPECT_GT(in_box, kWidth * kHeight / 4) << "most tile pixels are in the box";
        EXPECT_LT(in_box, kWidth * kHeight / 2) << "markers and the noisy patch are not";
      }
      for (int step : {2, 4}) {
        SCOPED_TRACE(testing::Message() << to_string(format) << " step " << step << " gains "
                                        << gains[0] << " " << gains[1] << " " << gains[2]);
        ASSERT_TRUE(labeler.label_sampled(levels.view(), classifier, step));
        const std::vector<Component> want(labeler.components().begin(), labeler.components().end());
        ASSERT_TRUE(labeler.label_sampled(yuv.view(), classifier, step));
        expect_same_components(labeler.components(), want);
      }
    }
  }
}

TEST_F(ComponentsTest, HalvedSweepRefusesNoiseAnotherSizeAndFindsNothingInGrey) {
  fill(10, 20, 29, 59, kRed);
  const Image grey = test::convert_rgb(frame, PixelFormat::kGray8);
  EXPECT_TRUE(labeler.label_sampled(grey.view(), classifier, 2));
  EXPECT_TRUE(labeler.components().empty());
  Image other(kWidth + 2, kHeight, PixelFormat::kRgb24);
  EXPECT_FALSE(labeler.label_sampled(other.view(), classifier, 2));
  std::mt19937 rng(3);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) test::put_rgb(&frame, x, y, (rng() & 1) ? kRed : kGreen);
  EXPECT_FALSE(labeler.label_sampled(frame.view(), classifier, 2));
  EXPECT_TRUE(labeler.components().empty());
}

TEST_F(ComponentsTest, FrameOfAnotherSizeIsRefused) {
  Image other(kWidth + 2, kHeight, PixelFormat::kRgb24);
  EXPECT_FALSE(labeler.label(other.view(), classifier));
}

}  // namespace
}  // namespace ceilpose
