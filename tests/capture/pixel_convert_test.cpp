// to_rgb24: the conversions the recorder (and any RGB-only consumer) relies on.
#include "capture/pixel_convert.h"

#include <gtest/gtest.h>

namespace ceilpose::capture {
namespace {

TEST(PixelConvert, YuyvNeutralGreyBecomesEqualRgb) {
  Image yuyv(4, 2, PixelFormat::kYuyv);
  for (size_t i = 0; i < yuyv.size_bytes(); i += 2) {
    yuyv.data()[i] = 150;      // Y
    yuyv.data()[i + 1] = 128;  // U or V: no colour
  }
  Image rgb;
  ASSERT_TRUE(to_rgb24(yuyv.view(), &rgb));
  ASSERT_EQ(rgb.format(), PixelFormat::kRgb24);
  ASSERT_EQ(rgb.width(), 4);
  // Cameras send video-range YUV (BT.601): Y 16..235 maps to 0..255, so
  // Y = 150 is 1.164 * (150 - 16) = 156 on every channel.
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(rgb.data()[c], 156, 1);
}

TEST(PixelConvert, BgrChannelsAreSwappedToRgb) {
  Image bgr(2, 1, PixelFormat::kBgr24);
  const uint8_t px[6] = {10, 20, 30, 40, 50, 60};
  std::copy(px, px + 6, bgr.data());
  Image rgb;
  ASSERT_TRUE(to_rgb24(bgr.view(), &rgb));
  EXPECT_EQ(rgb.data()[0], 30);
  EXPECT_EQ(rgb.data()[1], 20);
  EXPECT_EQ(rgb.data()[2], 10);
  EXPECT_EQ(rgb.data()[3], 60);
}

TEST(PixelConvert, RowPaddingOfTheSourceIsHonoured) {
  // A driver may pad rows (bytesperline > width * bpp).
  std::vector<uint8_t> padded(2 * 8, 0);
  const uint8_t row0[6] = {1, 2, 3, 4, 5, 6};
  const uint8_t row1[6] = {7, 8, 9, 10, 11, 12};
  std::copy(row0, row0 + 6, padded.begin());
  std::copy(row1, row1 + 6, padded.begin() + 8);
  const ImageView view{padded.data(), 2, 2, 8, PixelFormat::kRgb24, padded.size()};
  Image rgb;
  ASSERT_TRUE(to_rgb24(view, &rgb));
  EXPECT_EQ(rgb.stride_bytes(), 6);
  EXPECT_EQ(rgb.row(1)[0], 7);
  EXPECT_EQ(rgb.row(1)[5], 12);
}

TEST(PixelConvert, GreyStaysGreyUnlessRgbIsAskedFor) {
  Image grey(3, 1, PixelFormat::kGray8);
  grey.data()[0] = 90;
  Image out;
  ASSERT_TRUE(to_rgb24(grey.view(), &out));
  EXPECT_EQ(out.format(), PixelFormat::kGray8);
  ASSERT_TRUE(to_rgb24(grey.view(), &out, /*keep_gray=*/false));
  EXPECT_EQ(out.format(), PixelFormat::kRgb24);
  EXPECT_EQ(out.data()[1], 90);
}

TEST(PixelConvert, CompressedFramesAreRefusedWithAReason) {
  const uint8_t jpeg[4] = {0xFF, 0xD8, 0xFF, 0xD9};
  const ImageView view{jpeg, 2, 2, 0, PixelFormat::kMjpeg, 4};
  Image out;
  auto r = to_rgb24(view, &out);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("MJPEG"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace ceilpose::capture
