// read_rgb_2x2, read_darkest_2x2 and pixel_edge_level, the bilinear
// samples' readers (dot slots, rectangle edges), give each pixel exactly as
// read_rgb does, in every format: random bytes, every position, odd and even
// columns and rows.
#include "core/pixel_read.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

namespace ceilpose {
namespace {

// Calls check(view, x, y, message) for every 2x2 block's top-left pixel of a
// 10x6 image of random bytes in every uncompressed format.
template <typename Check>
void for_every_block(uint32_t seed, Check&& check) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> byte(0, 255);
  for (PixelFormat format : {PixelFormat::kRgb24, PixelFormat::kBgr24, PixelFormat::kYuyv,
                             PixelFormat::kNv12, PixelFormat::kYuv420, PixelFormat::kGray8}) {
    Image image(10, 6, format);
    for (size_t i = 0; i < image.size_bytes(); ++i)
      image.data()[i] = static_cast<uint8_t>(byte(rng));
    const ImageView view = image.view();
    for (int y = 0; y + 1 < view.height; ++y)
      for (int x = 0; x + 1 < view.width; ++x)
        check(view, x, y,
              "format " + std::to_string(static_cast<int>(format)) + " at " + std::to_string(x) +
                  "," + std::to_string(y));
  }
}

TEST(PixelRead, TwoByTwoBlocksAreReadRgbOfTheirFourPixelsInEveryFormat) {
  for_every_block(7, [](const ImageView& view, int x, int y, const std::string& where) {
    std::array<Rgb, 4> block;
    read_rgb_2x2(view, x, y, &block);
    for (int k = 0; k < 4; ++k) {
      uint8_t r = 0, g = 0, b = 0;
      read_rgb(view, x + (k & 1), y + (k >> 1), &r, &g, &b);
      EXPECT_EQ(block[k].r, r) << where << " pixel " << k;
      EXPECT_EQ(block[k].g, g) << where << " pixel " << k;
      EXPECT_EQ(block[k].b, b) << where << " pixel " << k;
    }
  });
}

// yuv_darkest takes the least chroma part instead of converting: the same
// byte as the least of yuv_to_rgb's three for every (y, u, v).
TEST(PixelRead, YuvDarkestIsTheLeastOfTheThreeChannelsForEveryYuv) {
  int mismatches = 0;
  for (int y = 0; y < 256; ++y)
    for (int u = 0; u < 256; ++u)
      for (int v = 0; v < 256; ++v) {
        uint8_t r = 0, g = 0, b = 0;
        yuv_to_rgb(y, u, v, &r, &g, &b);
        mismatches += yuv_darkest(y, u, v) != std::min({r, g, b}) ? 1 : 0;
      }
  EXPECT_EQ(mismatches, 0);
}

TEST(PixelRead, TwoByTwoDarkestIsTheLeastChannelOfReadRgbInEveryFormat) {
  for_every_block(11, [](const ImageView& view, int x, int y, const std::string& where) {
    std::array<uint8_t, 4> block;
    read_darkest_2x2(view, x, y, &block);
    for (int k = 0; k < 4; ++k) {
      uint8_t r = 0, g = 0, b = 0;
      read_rgb(view, x + (k & 1), y + (k >> 1), &r, &g, &b);
      EXPECT_EQ(block[k], std::min({r, g, b})) << where << " pixel " << k;
    }
  });
}

// pixel_edge_level: RGB and BGR give the asked channel of read_rgb (or
// its BT.601 luma), grey its level, and YUV formats their luma byte in full range (the level a
// Y of 16 / 235 stands for: 0 / 255), whatever the chroma.
TEST(PixelRead, TwoByTwoEdgeLevelsAreTheChannelOrTheLumaInEveryFormat) {
  for_every_block(13, [](const ImageView& view, int x, int y, const std::string& where) {
    for (EdgeChannel channel : {EdgeChannel::kRed, EdgeChannel::kGreen, EdgeChannel::kLuma}) {
      for (int k = 0; k < 4; ++k) {
        const int px = x + (k & 1), py = y + (k >> 1);
        uint8_t level = 0;
        with_pixel_format(view.format, [&](auto tag) {
          level = pixel_edge_level<decltype(tag)::value>(view, px, py, channel);
        });
        uint8_t r = 0, g = 0, b = 0;
        read_rgb(view, px, py, &r, &g, &b);
        uint8_t expected = channel == EdgeChannel::kRed     ? r
                           : channel == EdgeChannel::kGreen ? g
                                                            : rgb_luma(r, g, b);
        if (view.format == PixelFormat::kYuyv) {
          expected = yuv_channel(yuv_luma_part(view.row(py)[2 * px]), 0);
        } else if (is_yuv420(view.format)) {
          expected = yuv_channel(yuv_luma_part(view.row(py)[px]), 0);
        }
        EXPECT_EQ(level, expected) << where << " pixel " << k;
      }
    }
  });
  EXPECT_EQ(yuv_channel(yuv_luma_part(16), 0), 0);
  EXPECT_EQ(yuv_channel(yuv_luma_part(235), 0), 255);
}

// yuv_byte rounds as std::lround does, clamps to a byte, and sends a NaN to 0
// (a cast of NaN to int would be undefined).
TEST(PixelRead, YuvByteRoundsHalvesUpClampsAndSendsNanToZero) {
  for (double x = -3.0; x <= 258.0; x += 0.125) {
    const long expected = std::clamp(std::lround(x), 0L, 255L);
    EXPECT_EQ(yuv_byte(x), expected) << "x " << x;
  }
  EXPECT_EQ(yuv_byte(std::nextafter(0.5, 0.0)), 0);
  EXPECT_EQ(yuv_byte(0.5), 1);
  EXPECT_EQ(yuv_byte(std::numeric_limits<double>::quiet_NaN()), 0);
  EXPECT_EQ(yuv_byte(std::numeric_limits<double>::infinity()), 255);
  EXPECT_EQ(yuv_byte(-std::numeric_limits<double>::infinity()), 0);
}

}  // namespace
}  // namespace ceilpose
