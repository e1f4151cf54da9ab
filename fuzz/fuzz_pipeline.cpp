// The whole frame path (detection, positioning, filter) on arbitrary pixels
// of a valid size: a pose or a refusal, never a crash, and a valid pose is
// finite and unrefused. The first byte picks the pixel format, the rest are
// the pixels (cycled to fill the frame). Each input gets a fresh Localizer,
// so that a crash reproduces from its artifact alone.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "pipeline/localizer.h"

namespace {

using namespace ceilpose;

// The invariant every sink relies on: nothing non-finite, no refusal, in a
// valid estimate.
void check_estimate(const PoseEstimate& e, const char* which) {
  if (!e.valid) return;
  bool finite =
      std::isfinite(e.pose.x_m) && std::isfinite(e.pose.y_m) && std::isfinite(e.pose.yaw_rad);
  for (double c : e.covariance) finite = finite && std::isfinite(c);
  if (finite && e.refusal == Refusal::kNone) return;
  std::fprintf(stderr, "fuzz_pipeline: a valid %s pose is not finite or carries a refusal\n",
               which);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  constexpr int kWidth = 160, kHeight = 120, kFrames = 2;
  static std::vector<uint8_t> pixels(static_cast<size_t>(kWidth) * kHeight * 3);
  if (size < 2) return 0;
  PipelineConfig config;
  config.intrinsics.width = kWidth;
  config.intrinsics.height = kHeight;
  config.intrinsics.fx = config.intrinsics.fy = 132.5;
  config.intrinsics.cx = 79.5;
  config.intrinsics.cy = 59.5;
  config.intrinsics.readout_ms = 20.0;
  Localizer localizer(config);
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
  // The same frame twice, 33 ms apart: the filter's update runs too.
  for (int i = 0; i < kFrames; ++i) {
    FrameInfo frame;
    frame.timestamp_ns = (i + 1) * 33'333'333LL;
    const Localization& out = localizer.localize(view, frame);
    check_estimate(out.measured, "measured");
    check_estimate(out.published, "published");
  }
  return 0;
}
