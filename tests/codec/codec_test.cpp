// codec/ against OpenCV's imgcodecs, an independent PNG and JPEG codec, on
// real photographs (Debian's opencv-doc) and on images made here; and on
// broken, truncated and unsupported files.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "codec/jpeg_codec.h"
#include "codec/png_codec.h"

namespace ceilpose::codec {
namespace {

const std::string kPhotos = "/usr/share/doc/opencv-doc/examples/data/";

std::vector<uint8_t> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// OpenCV's decode in the layout codec/ gives (RGB, or grey).
cv::Mat reference_decode(const std::vector<uint8_t>& bytes, bool grey) {
  cv::Mat decoded = cv::imdecode(bytes, grey ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
  if (!grey) cv::cvtColor(decoded, decoded, cv::COLOR_BGR2RGB);
  return decoded;
}

cv::Mat as_mat(const Image& img) {
  return cv::Mat(img.height(), img.width(), img.format() == PixelFormat::kGray8 ? CV_8UC1 : CV_8UC3,
                 const_cast<uint8_t*>(img.data()), static_cast<size_t>(img.stride_bytes()));
}

double max_difference(const cv::Mat& a, const cv::Mat& b) {
  double max = 0.0;
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  cv::minMaxLoc(diff.reshape(1), nullptr, &max);
  return max;
}

// A scene with edges and gradients in every channel, `channels` 1 or 3.
Image test_image(int width, int height, PixelFormat format, uint32_t seed) {
  Image img(width, height, format);
  std::mt19937 rng(seed);
  const int channels = bytes_per_pixel(format);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c) {
        const bool square = ((x / 16) + (y / 16)) % 2 == 0;
        img.row(y)[x * channels + c] =
            static_cast<uint8_t>((square ? 200 : 40) + (x * (c + 1) + y) % 37 + rng() % 3);
      }
    }
  }
  return img;
}

TEST(JpegCodec, RealPhotographsDecodeAsOpenCvDoes) {
  JpegCodec codec;
  for (const char* name :
       {"baboon.jpg", "HappyFish.jpg", "left01.jpg", "basketball1.png", "pic1.png"}) {
    const std::string path = kPhotos + name;
    ASSERT_TRUE(std::filesystem::exists(path)) << path << ": run scripts/setup (opencv-doc)";
    const auto bytes = read_bytes(path);
    const bool png = std::string(name).ends_with(".png");
    Image ours;
    Result<void> decoded = [&]() -> Result<void> {
      if (png) return decode_png(bytes.data(), bytes.size(), &ours);
      auto head = codec.header(bytes.data(), bytes.size());
      if (!head) return head.error();
      return codec.decode(bytes.data(), bytes.size(),
                          head->grey ? PixelFormat::kGray8 : PixelFormat::kRgb24, &ours);
    }();
    ASSERT_TRUE(decoded) << name << ": " << decoded.error().message;
    const cv::Mat reference = reference_decode(bytes, ours.format() == PixelFormat::kGray8);
    ASSERT_EQ(reference.cols, ours.width()) << name;
    ASSERT_EQ(reference.rows, ours.height()) << name;
    // Both are libjpeg-turbo / libpng with the same defaults: identical.
    EXPECT_EQ(max_difference(reference, as_mat(ours)), 0.0) << name;
  }
}

TEST(JpegCodec, ScaledDecodeIsTheFullDecodeAveraged) {
  const auto bytes = read_bytes(kPhotos + "baboon.jpg");
  ASSERT_FALSE(bytes.empty());
  JpegCodec codec;
  Image full;
  ASSERT_TRUE(codec.decode(bytes.data(), bytes.size(), PixelFormat::kRgb24, &full));
  for (int denominator : {2, 4, 8}) {
    Image small;
    const auto decoded =
        codec.decode(bytes.data(), bytes.size(), PixelFormat::kRgb24, &small, denominator);
    ASSERT_TRUE(decoded) << decoded.error().message;
    EXPECT_EQ(small.width(), (full.width() + denominator - 1) / denominator);
    EXPECT_EQ(small.height(), (full.height() + denominator - 1) / denominator);
    cv::Mat averaged;
    cv::resize(as_mat(full), averaged, cv::Size(small.width(), small.height()), 0, 0,
               cv::INTER_AREA);
    cv::Mat diff;
    cv::absdiff(averaged, as_mat(small), diff);
    // Measured 2.1-3.3 levels mean: DCT scaling is not a box filter.
    EXPECT_LT(cv::mean(diff.reshape(1))[0], 5.0) << "1/" << denominator;
  }
  Image out;
  const auto refused = codec.decode(bytes.data(), bytes.size(), PixelFormat::kRgb24, &out, 3);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("1/3"), std::string::npos) << refused.error().message;
}

TEST(JpegCodec, EncodesWhatOpenCvDecodesCloseToTheSource) {
  JpegCodec codec;
  for (PixelFormat format : {PixelFormat::kRgb24, PixelFormat::kBgr24, PixelFormat::kGray8}) {
    const Image src = test_image(320, 240, format, 7);
    std::vector<uint8_t> jpeg;
    const auto encoded = codec.encode(src.view(), 95, &jpeg);
    ASSERT_TRUE(encoded) << encoded.error().message;
    const bool grey = format == PixelFormat::kGray8;
    auto head = codec.header(jpeg.data(), jpeg.size());
    ASSERT_TRUE(head);
    EXPECT_EQ(head->grey, grey) << to_string(format);
    cv::Mat reference = cv::imdecode(jpeg, grey ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
    if (format == PixelFormat::kRgb24) cv::cvtColor(reference, reference, cv::COLOR_BGR2RGB);
    const double psnr = cv::PSNR(reference, as_mat(src));
    // Measured 37-44 dB at quality 95 on this pattern (4:2:0 chroma).
    EXPECT_GT(psnr, 33.0) << to_string(format);
  }
}

// What a subsampled JPEG decodes to is marked as such (its colour channels
// carry half-resolution chroma: rectangle_ends measures edges in luma
// there); a grey one, and an image resized for other pixels, are not.
TEST(JpegCodec, DecodedSubsampledChromaIsMarkedOnTheImage) {
  JpegCodec codec;
  const Image src = test_image(64, 48, PixelFormat::kRgb24, 3);
  std::vector<uint8_t> jpeg;
  ASSERT_TRUE(codec.encode(src.view(), 90, &jpeg));  // 4:2:0, as cameras send
  Image out;
  ASSERT_TRUE(codec.decode(jpeg.data(), jpeg.size(), PixelFormat::kRgb24, &out));
  EXPECT_TRUE(out.view().chroma_halved);
  out.resize(64, 48, PixelFormat::kRgb24);
  EXPECT_FALSE(out.view().chroma_halved);
  // The same frame through decode_fixed (the V4L2 MJPEG path).
  ASSERT_TRUE(codec.decode_fixed(jpeg.data(), jpeg.size(), &out));
  EXPECT_TRUE(out.view().chroma_halved);
  const Image grey = test_image(64, 48, PixelFormat::kGray8, 3);
  ASSERT_TRUE(codec.encode(grey.view(), 90, &jpeg));
  ASSERT_TRUE(codec.decode(jpeg.data(), jpeg.size(), PixelFormat::kGray8, &out));
  EXPECT_FALSE(out.view().chroma_halved);
}

TEST(JpegCodec, TruncatedOrCorruptStreamsAreErrorsNotGreyPictures) {
  JpegCodec codec;
  const Image src = test_image(160, 120, PixelFormat::kRgb24, 3);
  std::vector<uint8_t> jpeg;
  ASSERT_TRUE(codec.encode(src.view(), 90, &jpeg));
  Image out(160, 120, PixelFormat::kRgb24);
  const uint8_t* storage = out.data();
  const std::vector<uint8_t> truncated(jpeg.begin(), jpeg.begin() + jpeg.size() * 2 / 3);
  const auto cut = codec.decode_fixed(truncated.data(), truncated.size(), &out);
  ASSERT_FALSE(cut);
  EXPECT_NE(cut.error().message.find("corrupt JPEG"), std::string::npos) << cut.error().message;
  std::vector<uint8_t> noise(jpeg.size());
  std::mt19937 rng(1);
  for (auto& b : noise) b = static_cast<uint8_t>(rng());
  const auto random = codec.decode_fixed(noise.data(), noise.size(), &out);
  ASSERT_FALSE(random);
  EXPECT_NE(random.error().message.find("not JPEG"), std::string::npos) << random.error().message;
  // A valid stream of another size: refused in place, nothing reallocated.
  Image other(80, 60, PixelFormat::kRgb24);
  const auto wrong = codec.decode_fixed(jpeg.data(), jpeg.size(), &other);
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.error().message.find("160x120 where 80x60"), std::string::npos)
      << wrong.error().message;
  ASSERT_TRUE(codec.decode_fixed(jpeg.data(), jpeg.size(), &out));
  EXPECT_EQ(out.data(), storage);
  EXPECT_FALSE(codec.decode(jpeg.data(), 0, PixelFormat::kRgb24, &out));
}

TEST(PngCodec, RoundTripsExactlyAndOpenCvReadsIt) {
  for (PixelFormat format : {PixelFormat::kGray8, PixelFormat::kRgb24, PixelFormat::kBgr24}) {
    // A view with padded rows, as a capture buffer has.
    const Image src = test_image(101, 37, format, 11);
    const int row_bytes = src.stride_bytes();
    std::vector<uint8_t> padded(static_cast<size_t>(row_bytes + 13) * 37);
    for (int y = 0; y < 37; ++y)
      std::copy_n(src.view().row(y), row_bytes,
                  padded.data() + static_cast<size_t>(y) * (row_bytes + 13));
    const ImageView view{padded.data(), 101, 37, row_bytes + 13, format, padded.size()};
    std::vector<uint8_t> png;
    const auto encoded = encode_png(view, 1, &png);
    ASSERT_TRUE(encoded) << encoded.error().message;
    Image back;
    const auto decoded = decode_png(png.data(), png.size(), &back);
    ASSERT_TRUE(decoded) << decoded.error().message;
    const bool grey = format == PixelFormat::kGray8;
    ASSERT_EQ(back.format(), grey ? PixelFormat::kGray8 : PixelFormat::kRgb24);
    cv::Mat expected = as_mat(src).clone();
    if (format == PixelFormat::kBgr24) cv::cvtColor(expected, expected, cv::COLOR_BGR2RGB);
    EXPECT_EQ(max_difference(expected, as_mat(back)), 0.0) << to_string(format);
    EXPECT_EQ(max_difference(expected, reference_decode(png, grey)), 0.0) << to_string(format);
  }
}

TEST(PngCodec, RefusesWhatTheRecordingFormatDoesNotCarry) {
  std::vector<uint8_t> alpha, deep;
  cv::imencode(".png", cv::Mat(8, 8, CV_8UC4, cv::Scalar(1, 2, 3, 4)), alpha);
  cv::imencode(".png", cv::Mat(8, 8, CV_16UC1, cv::Scalar(1000)), deep);
  Image out;
  const auto a = decode_png(alpha.data(), alpha.size(), &out);
  ASSERT_FALSE(a);
  EXPECT_NE(a.error().message.find("alpha"), std::string::npos) << a.error().message;
  const auto d = decode_png(deep.data(), deep.size(), &out);
  ASSERT_FALSE(d);
  EXPECT_NE(d.error().message.find("16-bit"), std::string::npos) << d.error().message;
  std::vector<uint8_t> png;
  ASSERT_TRUE(encode_png(test_image(40, 30, PixelFormat::kRgb24, 5).view(), 6, &png));
  const std::vector<uint8_t> cut(png.begin(), png.begin() + png.size() / 2);
  const auto c = decode_png(cut.data(), cut.size(), &out);
  ASSERT_FALSE(c);
  EXPECT_NE(c.error().message.find("corrupt PNG"), std::string::npos) << c.error().message;
  const Image yuyv(4, 4, PixelFormat::kYuyv);
  const auto y = encode_png(yuyv.view(), 1, &png);
  ASSERT_FALSE(y);
  EXPECT_NE(y.error().message.find("YUYV"), std::string::npos) << y.error().message;
}

}  // namespace
}  // namespace ceilpose::codec
