// read_rgb_2x2, the bilinear samples' reader (dot slots, rectangle edges),
// gives each of its four pixels exactly as read_rgb does, in every format:
// random bytes, every position, odd and even columns and rows.
#include "core/pixel_read.h"

#include <gtest/gtest.h>

#include <random>

namespace ceilpose {
namespace {

TEST(PixelRead, TwoByTwoBlocksAreReadRgbOfTheirFourPixelsInEveryFormat) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  for (PixelFormat format : {PixelFormat::kRgb24, PixelFormat::kBgr24, PixelFormat::kYuyv,
                             PixelFormat::kNv12, PixelFormat::kYuv420, PixelFormat::kGray8}) {
    Image image(10, 6, format);
    for (size_t i = 0; i < image.size_bytes(); ++i)
      image.data()[i] = static_cast<uint8_t>(byte(rng));
    const ImageView view = image.view();
    for (int y = 0; y + 1 < view.height; ++y) {
      for (int x = 0; x + 1 < view.width; ++x) {
        std::array<Rgb, 4> block;
        read_rgb_2x2(view, x, y, &block);
        for (int k = 0; k < 4; ++k) {
          uint8_t r = 0, g = 0, b = 0;
          read_rgb(view, x + (k & 1), y + (k >> 1), &r, &g, &b);
          EXPECT_EQ(block[k].r, r) << static_cast<int>(format) << " " << x << "," << y << " " << k;
          EXPECT_EQ(block[k].g, g) << static_cast<int>(format) << " " << x << "," << y << " " << k;
          EXPECT_EQ(block[k].b, b) << static_cast<int>(format) << " " << x << "," << y << " " << k;
        }
      }
    }
  }
}

}  // namespace
}  // namespace ceilpose
