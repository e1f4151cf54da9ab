#pragma once
// Non-owning and owning 8-bit image types shared by capture, sim and pipeline.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ceilpose {

// Pixel layouts a camera can deliver. MJPEG is compressed: capture decodes it
// before the pipeline sees the frame.
enum class PixelFormat : uint8_t { kGray8, kRgb24, kBgr24, kYuyv, kMjpeg };

inline int bytes_per_pixel(PixelFormat f) {
  switch (f) {
    case PixelFormat::kGray8:
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

const char* to_string(PixelFormat f);

struct ImageView {
  const uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  int stride_bytes = 0;
  PixelFormat format = PixelFormat::kRgb24;
  size_t size_bytes = 0;  // for compressed formats: the payload length

  bool empty() const { return data == nullptr || width <= 0 || height <= 0; }
  const uint8_t* row(int y) const { return data + static_cast<ptrdiff_t>(y) * stride_bytes; }
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
    pixels_.resize(static_cast<size_t>(stride_bytes_) * static_cast<size_t>(height));
  }
  int width() const { return width_; }
  int height() const { return height_; }
  int stride_bytes() const { return stride_bytes_; }
  PixelFormat format() const { return format_; }
  uint8_t* data() { return pixels_.data(); }
  const uint8_t* data() const { return pixels_.data(); }
  uint8_t* row(int y) { return pixels_.data() + static_cast<size_t>(y) * stride_bytes_; }
  size_t size_bytes() const { return pixels_.size(); }
  ImageView view() const {
    return ImageView{pixels_.data(), width_, height_, stride_bytes_, format_, pixels_.size()};
  }

 private:
  std::vector<uint8_t> pixels_;
  int width_ = 0;
  int height_ = 0;
  int stride_bytes_ = 0;
  PixelFormat format_ = PixelFormat::kRgb24;
};

}  // namespace ceilpose
