#include "pipeline/color_classifier.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "tests/pipeline/detect_scene_support.h"

namespace ceilpose {
namespace {

class ColorClassifierTest : public ::testing::Test {
 protected:
  CeilingLayout layout;
  DetectorParams params;
  ColorClassifier classifier{params, layout.tile};
};

TEST_F(ColorClassifierTest, PrintedColoursGetTheirClass) {
  EXPECT_EQ(classifier.classify(200, 30, 40), PixelClass::kRed);
  EXPECT_EQ(classifier.classify(40, 160, 70), PixelClass::kGreen);
  EXPECT_EQ(classifier.classify(25, 25, 25), PixelClass::kDark);
  EXPECT_EQ(classifier.classify(215, 215, 205), PixelClass::kBackground);
  EXPECT_EQ(classifier.classify(170, 170, 170), PixelClass::kBackground);
  EXPECT_EQ(classifier.classify(255, 255, 255), PixelClass::kBackground);
}

TEST_F(ColorClassifierTest, ValueDoesNotChangeTheColour) {
  // Hue and saturation define the colour; a darker or brighter print of it
  // (above the dark level) stays that colour.
  for (double scale : {0.6, 0.8, 1.0, 1.2}) {
    auto level = [scale](int v) { return static_cast<uint8_t>(std::min(255.0, v * scale)); };
    EXPECT_EQ(classifier.classify(level(200), level(30), level(40)), PixelClass::kRed) << scale;
    EXPECT_EQ(classifier.classify(level(40), level(160), level(70)), PixelClass::kGreen) << scale;
  }
}

TEST_F(ColorClassifierTest, SharedEdgePixelGoesToTheColourCoveringMore) {
  auto mix = [](double red_share, int r, int g) {
    return static_cast<uint8_t>(std::lround(red_share * r + (1.0 - red_share) * g));
  };
  EXPECT_EQ(classifier.classify(mix(0.7, 200, 40), mix(0.7, 30, 160), mix(0.7, 40, 70)),
            PixelClass::kRed);
  EXPECT_EQ(classifier.classify(mix(0.3, 200, 40), mix(0.3, 30, 160), mix(0.3, 40, 70)),
            PixelClass::kGreen);
}

TEST_F(ColorClassifierTest, ColourCastIsNormalisedAwayByTheTileReference) {
  // A strong blue cast: the tile reads bluish and the red rectangle purple.
  test::Lighting cast;
  cast.cast = {0.75, 1.0, 1.25};
  test::CraftedMarker marker;
  marker.centre_u_px = 160.0;
  marker.centre_v_px = 120.0;
  const Image frame = test::render_markers(320, 240, std::span(&marker, 1), layout, cast);
  ASSERT_TRUE(classifier.adapt(frame.view()));
  EXPECT_LT(classifier.gains()[2], classifier.gains()[0]);
  // With West image down, East (the red rectangle) is image up.
  uint8_t r = 0, g = 0, b = 0;
  read_rgb(frame.view(), 160, 120 - 15, &r, &g, &b);
  EXPECT_EQ(classifier.classify(r, g, b), PixelClass::kRed);
  read_rgb(frame.view(), 160, 120 + 15, &r, &g, &b);
  EXPECT_EQ(classifier.classify(r, g, b), PixelClass::kGreen);
  read_rgb(frame.view(), 20, 20, &r, &g, &b);
  EXPECT_EQ(classifier.classify(r, g, b), PixelClass::kBackground);
}

// A cast given as sRGB-level gains, as Lighting's linear-light one.
test::Lighting srgb_cast(double r, double g, double b) {
  test::Lighting lighting;
  lighting.cast = {std::pow(r, 2.2), std::pow(g, 2.2), std::pow(b, 2.2)};
  return lighting;
}

Image marker_frame(const CeilingLayout& layout, const test::Lighting& lighting) {
  test::CraftedMarker marker;
  marker.centre_u_px = 160.0;
  marker.centre_v_px = 120.0;
  return test::render_markers(320, 240, std::span(&marker, 1), layout, lighting);
}

void fill(Image* image, int x0, int y0, int x1, int y1, Rgb colour) {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) test::put_rgb(image, x, y, colour);
}

std::vector<PixelClass> classes_of(const ColorClassifier& classifier, const Image& frame) {
  std::vector<PixelClass> out;
  for (int y = 0; y < frame.height(); ++y)
    for (int x = 0; x < frame.width(); ++x) {
      uint8_t r = 0, g = 0, b = 0;
      read_rgb(frame.view(), x, y, &r, &g, &b);
      out.push_back(classifier.classify(r, g, b));
    }
  return out;
}

TEST_F(ColorClassifierTest, StrongWarmCastWithFixtureAndClutterStillFindsTheTile) {
  // (1.35, 1, 0.65) on sRGB levels: the tile reads (255, 215, 133),
  // saturation 0.48. A clipped white fixture (mean 255) and red and green
  // clutter beside the marker must not become the reference.
  Image frame = marker_frame(layout, srgb_cast(1.35, 1.0, 0.65));
  uint8_t tr = 0, tg = 0, tb = 0;
  read_rgb(frame.view(), 5, 5, &tr, &tg, &tb);
  fill(&frame, 240, 0, 320, 60, Rgb{255, 255, 255});
  fill(&frame, 0, 180, 60, 240, Rgb{255, 40, 26});
  fill(&frame, 250, 180, 320, 240, Rgb{54, 160, 45});
  ASSERT_TRUE(classifier.adapt(frame.view()));
  EXPECT_NEAR(classifier.reference()[0], tr, 3.0);
  EXPECT_NEAR(classifier.reference()[1], tg, 3.0);
  EXPECT_NEAR(classifier.reference()[2], tb, 3.0);
  uint8_t r = 0, g = 0, b = 0;
  read_rgb(frame.view(), 160, 120 - 15, &r, &g, &b);
  EXPECT_EQ(classifier.classify(r, g, b), PixelClass::kRed);
  read_rgb(frame.view(), 160, 120 + 15, &r, &g, &b);
  EXPECT_EQ(classifier.classify(r, g, b), PixelClass::kGreen);
  EXPECT_EQ(classifier.classify(tr, tg, tb), PixelClass::kBackground);
}

TEST_F(ColorClassifierTest, AFrameIsClassifiedAlikeWhateverFrameCameBefore) {
  // SPEC §5: without filtering every frame is solved on its own, so the
  // normalisation may not carry over from the previous frame, also when a
  // frame has no tile to adapt to.
  const Image warm = marker_frame(layout, srgb_cast(1.3, 1.0, 0.7));
  const Image cool = marker_frame(layout, srgb_cast(0.7, 1.0, 1.3));
  const Image black(320, 240, PixelFormat::kRgb24);
  for (const Image* frame : {&warm, &cool, &black}) {
    ColorClassifier fresh(params, layout.tile);
    const bool adapted = fresh.adapt(frame->view());
    EXPECT_EQ(adapted, frame != &black);
    const std::vector<PixelClass> expected = classes_of(fresh, *frame);
    for (const Image* before : {&warm, &cool, &black}) {
      ColorClassifier after(params, layout.tile);
      after.adapt(before->view());
      EXPECT_EQ(after.adapt(frame->view()), adapted);
      EXPECT_EQ(after.gains(), fresh.gains());
      EXPECT_TRUE(classes_of(after, *frame) == expected);
    }
  }
}

TEST_F(ColorClassifierTest, AdaptFallsBackToUnitGainsOnAFrameWithoutTile) {
  ASSERT_TRUE(classifier.adapt(marker_frame(layout, srgb_cast(1.3, 1.0, 0.7)).view()));
  ASSERT_NE(classifier.gains(), (std::array<float, 3>{1.0f, 1.0f, 1.0f}));
  Image black(64, 48, PixelFormat::kRgb24);
  EXPECT_FALSE(classifier.adapt(black.view()));
  EXPECT_EQ(classifier.gains(), (std::array<float, 3>{1.0f, 1.0f, 1.0f}));
}

TEST_F(ColorClassifierTest, YuvFormatsReadBackThePrintedColours) {
  for (PixelFormat format : {PixelFormat::kYuyv, PixelFormat::kNv12, PixelFormat::kYuv420}) {
    for (Rgb c : {layout.red, layout.green, layout.tile}) {
      Image rgb(4, 3, PixelFormat::kRgb24);
      for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 4; ++x) test::put_rgb(&rgb, x, y, c);
      const Image yuv = test::convert_rgb(rgb, format);
      for (auto [x, y] : {std::pair{1, 0}, std::pair{2, 1}, std::pair{3, 2}}) {
        uint8_t r = 0, g = 0, b = 0;
        read_rgb(yuv.view(), x, y, &r, &g, &b);
        EXPECT_NEAR(r, c.r, 2) << to_string(format) << " " << x << "," << y;
        EXPECT_NEAR(g, c.g, 2) << to_string(format) << " " << x << "," << y;
        EXPECT_NEAR(b, c.b, 2) << to_string(format) << " " << x << "," << y;
      }
    }
  }
}

TEST_F(ColorClassifierTest, GreyPixelsAreNeverRedOrGreen) {
  for (int v = 0; v < 256; ++v) {
    const auto c = static_cast<uint8_t>(v);
    const PixelClass k = classifier.classify(c, c, c);
    EXPECT_TRUE(k == PixelClass::kBackground || k == PixelClass::kDark) << v;
  }
}

// A YUV sweep computes each pixel's cell (ColorClassifier::cell_of) where a
// sparse read looks it up: both must be the normalised level (level × gain,
// rounded, at most 255) quantised to kCells, for every level and every gain
// the classifier holds, and the tables must be the cells in their places.
TEST_F(ColorClassifierTest, CellArithmeticIsTheQuantisedNormalisedLevel) {
  constexpr int kShift = 8 - ColorClassifier::kBitsPerChannel;
  const auto lo = static_cast<int32_t>(ColorClassifier::kMinGain * 65536.0f);
  const auto hi = static_cast<int32_t>(ColorClassifier::kMaxGain * 65536.0f) + 1;
  int wrong = 0;
  for (int32_t gain_q16 = lo; gain_q16 <= hi; gain_q16 += 7) {
    for (int level = 0; level < 256; ++level) {
      const int64_t normalised = std::min<int64_t>(255, (level * int64_t{gain_q16} + 32768) >> 16);
      wrong += ColorClassifier::cell_of(level, gain_q16) != (normalised >> kShift);
    }
  }
  EXPECT_EQ(wrong, 0);
  for (const std::array<float, 3> gains :
       {std::array<float, 3>{1.0f, 1.0f, 1.0f}, std::array<float, 3>{0.25f, 1.37f, 4.0f},
        std::array<float, 3>{0.1f, NAN, 9.0f}}) {
    classifier.set_gains(gains);
    const ColorClassifier::GainsQ16 q = classifier.gains_q16();
    for (int c = 0; c < 3; ++c) {
      EXPECT_GE(classifier.gains()[c], ColorClassifier::kMinGain) << c;
      EXPECT_LE(classifier.gains()[c], ColorClassifier::kMaxGain) << c;
    }
    for (int level = 0; level < 256; ++level) {
      EXPECT_EQ(classifier.table(0)[level],
                ColorClassifier::lut_index(ColorClassifier::cell_of(level, q.r), 0, 0));
      EXPECT_EQ(classifier.table(1)[level],
                ColorClassifier::lut_index(0, ColorClassifier::cell_of(level, q.g), 0));
      EXPECT_EQ(classifier.table(2)[level],
                ColorClassifier::lut_index(0, 0, ColorClassifier::cell_of(level, q.b)));
    }
  }
}

}  // namespace
}  // namespace ceilpose
