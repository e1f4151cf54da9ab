#pragma once
// Non-owning and owning 8-bit image types shared by capture, sim and pipeline.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ceilpose {

// Pixel layouts a camera can deliver. MJPEG is compressed: capture decodes it
// before the pipeline sees the frame. The 4:2:0 formats (Pi cameras through
// libcamera, many V4L2 ISPs) are planar, as V4L2's single-plane formats lay
// them out: the luma plane (height rows of stride_bytes), then the chroma at
// half resolution in both directions for each 2x2 block -- NV12 one plane of
// (height+1)/2 rows of interleaved U, V bytes with the luma's stride; YUV420
// (I420) a U plane then a V plane of (height+1)/2 rows of stride_bytes/2.
// Both hold stride_bytes x (height + (height+1)/2) bytes; width is even.
// One pixel's red, green and blue levels.
struct Rgb {
  uint8_t r, g, b;
};

enum class PixelFormat : uint8_t { kGray8, kRgb24, kBgr24, kYuyv, kMjpeg, kNv12, kYuv420 };

// YUYV (V4L2_PIX_FMT_YUYV): two pixels in four bytes, Y0 U Y1 V. Pixel x's
// luma is byte 2x of its row; its pair, from byte kYuyvPairBytes * (x / 2),
// holds the chroma both share.
inline constexpr int kYuyvPairBytes = 4;
inline constexpr int kYuyvUByte = 1;  // of a pair
inline constexpr int kYuyvVByte = 3;
inline constexpr int kYuyvSecondLumaByte = 2;

// Bytes per pixel of a row; for the 4:2:0 formats, of the luma plane's row.
inline int bytes_per_pixel(PixelFormat f) {
  switch (f) {
    case PixelFormat::kGray8:
    case PixelFormat::kNv12:
    case PixelFormat::kYuv420:
      return 1;
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24:
      return 3;
    case PixelFormat::kYuyv:
      return 2;
    case PixelFormat::kMjpeg:
      return 0;
  }
  return 0;
}

inline bool is_yuv420(PixelFormat f) {
  return f == PixelFormat::kNv12 || f == PixelFormat::kYuv420;
}

// Bytes an uncompressed frame occupies, every plane included.
inline size_t frame_bytes(PixelFormat f, int stride_bytes, int height) {
  const size_t rows = static_cast<size_t>(height) + (is_yuv420(f) ? (height + 1) / 2 : 0);
  return static_cast<size_t>(stride_bytes) * rows;
}

const char* to_string(PixelFormat f);

struct ImageView {
  const uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  int stride_bytes = 0;
  PixelFormat format = PixelFormat::kRgb24;
  size_t size_bytes = 0;  // for compressed formats: the payload length
  // RGB decoded from data whose chroma had half the resolution (a 4:2:0 or
  // 4:2:2 JPEG, as MJPEG cameras send): its colour channels carry that
  // chroma, blurred, and only a luma is sharp (pipeline/rectangle_ends.h).
  bool chroma_halved = false;

  bool empty() const { return data == nullptr || width <= 0 || height <= 0; }
  const uint8_t* row(int y) const { return data + static_cast<ptrdiff_t>(y) * stride_bytes; }
  // 4:2:0 chroma of luma row y (the layouts of PixelFormat). NV12: U of
  // pixel x at uv_row(y)[x & ~1], V at [x | 1]. YUV420: u_row(y)[x / 2],
  // v_row(y)[x / 2].
  const uint8_t* uv_row(int y) const {
    return row(height) + static_cast<ptrdiff_t>(y / 2) * stride_bytes;
  }
  const uint8_t* u_row(int y) const {
    return row(height) + static_cast<ptrdiff_t>(y / 2) * (stride_bytes / 2);
  }
  const uint8_t* v_row(int y) const {
    return row(height) + static_cast<ptrdiff_t>((height + 1) / 2 + y / 2) * (stride_bytes / 2);
  }
};

// An owning, tightly packed image. Allocates only in resize().
class Image {
 public:
  Image() = default;
  Image(int width, int height, PixelFormat format) { resize(width, height, format); }
  void resize(int width, int height, PixelFormat format) {
    width_ = width;
    height_ = height;
    format_ = format;
    stride_bytes_ = width * bytes_per_pixel(format);
    pixels_.resize(frame_bytes(format, stride_bytes_, height));
    chroma_halved_ = false;
  }
  // Set by whoever writes pixels decoded from subsampled chroma (ImageView).
  void set_chroma_halved(bool halved) { chroma_halved_ = halved; }
  int width() const { return width_; }
  int height() const { return height_; }
  int stride_bytes() const { return stride_bytes_; }
  PixelFormat format() const { return format_; }
  uint8_t* data() { return pixels_.data(); }
  const uint8_t* data() const { return pixels_.data(); }
  uint8_t* row(int y) { return pixels_.data() + static_cast<size_t>(y) * stride_bytes_; }
  size_t size_bytes() const { return pixels_.size(); }
  ImageView view() const {
    return ImageView{pixels_.data(), width_,         height_,       stride_bytes_,
                     format_,        pixels_.size(), chroma_halved_};
  }

 private:
  std::vector<uint8_t> pixels_;
  int width_ = 0;
  int height_ = 0;
  int stride_bytes_ = 0;
  PixelFormat format_ = PixelFormat::kRgb24;
  bool chroma_halved_ = false;
};

}  // namespace ceilpose
