// The whole frame path (detection, positioning, filter) on arbitrary pixels
// of a valid size: a pose or a refusal, never a crash. The first byte picks
// the pixel format, the rest are the pixels (cycled to fill the frame).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "pipeline/localizer.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace ceilpose;
  constexpr int kWidth = 160, kHeight = 120;
  static const std::unique_ptr<Localizer> localizer = [] {
    PipelineConfig config;
    config.intrinsics.width = kWidth;
    config.intrinsics.height = kHeight;
    config.intrinsics.fx = config.intrinsics.fy = 132.5;
    config.intrinsics.cx = 79.5;
    config.intrinsics.cy = 59.5;
    config.intrinsics.readout_ms = 20.0;
    return std::make_unique<Localizer>(config, LocalizerOptions{});
  }();
  static std::vector<uint8_t> pixels(static_cast<size_t>(kWidth) * kHeight * 3);
  static int64_t t_ns = 0;
  if (size < 2) return 0;
  const PixelFormat format = data[0] % 3 == 0   ? PixelFormat::kRgb24
                             : data[0] % 3 == 1 ? PixelFormat::kBgr24
                                                : PixelFormat::kGray8;
  const size_t bytes = static_cast<size_t>(kWidth) * kHeight * bytes_per_pixel(format);
  for (size_t k = 0; k < bytes; ++k) pixels[k] = data[1 + k % (size - 1)];
  ImageView view;
  view.data = pixels.data();
  view.width = kWidth;
  view.height = kHeight;
  view.stride_bytes = kWidth * static_cast<int>(bytes_per_pixel(format));
  view.format = format;
  view.size_bytes = bytes;
  FrameInfo frame;
  t_ns += 33'333'333;
  frame.timestamp_ns = t_ns;
  (void)localizer->localize(view, frame);
  return 0;
}
