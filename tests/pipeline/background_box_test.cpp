#include "pipeline/background_box.h"

#include <gtest/gtest.h>

#include <random>

#include "core/ceiling_layout.h"
#include "core/pixel_read.h"
#include "pipeline/color_classifier.h"

namespace ceilpose {
namespace {

// Every byte triple in the box, converted as a sweep converts a sample
// with its own chroma, is background: checked one by one, under unit
// gains, strong casts, under- and over-exposure, and other thresholds.
TEST(BackgroundBox, EverySampleInTheBoxIsBackground) {
  CeilingLayout layout;
  DetectorParams loose;  // a paler red and green than the defaults call colour
  loose.red_min_saturation = 0.15f;
  loose.green_min_saturation = 0.1f;
  loose.dark_max_value = 140;
  std::mt19937 rng(11);
  // Gains as adapt() sets them: the nominal tile over a measured raw tile
  // of 60..255 per channel (exposure and cast together).
  std::uniform_real_distribution<float> raw_tile(60.0f, 255.0f);
  const std::array<float, 3> nominal{static_cast<float>(layout.tile.r),
                                     static_cast<float>(layout.tile.g),
                                     static_cast<float>(layout.tile.b)};
  int boxes = 0;
  for (const DetectorParams& params : {DetectorParams{}, loose}) {
    ColorClassifier classifier(params, layout.tile);
    for (int trial = 0; trial < 12; ++trial) {
      const std::array<float, 3> gains =
          trial == 0 ? std::array<float, 3>{1.0f, 1.0f, 1.0f}
                     : std::array<float, 3>{nominal[0] / raw_tile(rng), nominal[1] / raw_tile(rng),
                                            nominal[2] / raw_tile(rng)};
      SCOPED_TRACE(testing::Message() << "gains " << gains[0] << " " << gains[1] << " " << gains[2]
                                      << " dark below " << params.dark_max_value);
      classifier.set_gains(gains);
      const YuvBox box = classifier.background_yuv();
      if (box.empty()) continue;
      ++boxes;
      int wrong = 0;
      for (int y = box.y_lo; y <= box.y_hi; ++y)
        for (int u = box.u_lo; u <= box.u_hi; ++u)
          for (int v = box.v_lo; v <= box.v_hi; ++v) {
            uint8_t r = 0, g = 0, b = 0;
            yuv_to_rgb(y, u, v, &r, &g, &b);
            wrong += classifier.classify(r, g, b) != PixelClass::kBackground;
          }
      EXPECT_EQ(wrong, 0);
    }
  }
  EXPECT_GE(boxes, 20) << "a box is proven under most gains";
}

// Under unit gains the box holds the nominal tile with room for a camera's
// read noise and shading: measured Y 147..255, U 116..132, V 121..137.
TEST(BackgroundBox, TheTileIsInABoxWithRoomForNoiseAndShading) {
  CeilingLayout layout;
  ColorClassifier classifier(DetectorParams{}, layout.tile);
  const YuvBox box = classifier.background_yuv();
  ASSERT_FALSE(box.empty());
  const int y = static_cast<int>(std::lround(
      16 + (65.738 * layout.tile.r + 129.057 * layout.tile.g + 25.064 * layout.tile.b) / 256));
  EXPECT_TRUE(box.contains(y, 124, 129)) << "the tile, Y " << y;
  EXPECT_LE(box.y_lo, y - 40);
  EXPECT_GE(box.u_hi - box.u_lo, 14);
  EXPECT_GE(box.v_hi - box.v_lo, 14);
  // Darker than the dots' threshold, or as coloured as a marker: outside.
  EXPECT_FALSE(box.contains(60, 128, 128));
  EXPECT_FALSE(box.contains(y, 128, 170));
}

// With no background near the tile (everything bright enough counts as
// red or green) no box is proven, and a sweep converts every sample.
TEST(BackgroundBox, NoBoxWhereTheTileIsNotBackground) {
  CeilingLayout layout;
  DetectorParams params;
  params.red_min_saturation = 0.0f;
  params.green_min_saturation = 0.0f;
  params.red_hue_min_deg = -180.0f;
  params.red_hue_max_deg = 180.0f;
  params.green_hue_min_deg = 0.0f;
  params.green_hue_max_deg = 360.0f;
  ColorClassifier classifier(params, layout.tile);
  EXPECT_TRUE(classifier.background_yuv().empty());
}

}  // namespace
}  // namespace ceilpose
