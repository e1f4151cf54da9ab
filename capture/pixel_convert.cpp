#include "capture/pixel_convert.h"

#include <cstring>
#include <opencv2/imgproc.hpp>

#include "core/pixel_read.h"

namespace ceilpose::capture {

Result<void> to_rgb24(const ImageView& in, Image* out, bool keep_gray) {
  if (in.empty()) return make_error("to_rgb24: empty image");
  const PixelFormat target =
      keep_gray && in.format == PixelFormat::kGray8 ? PixelFormat::kGray8 : PixelFormat::kRgb24;
  if (out->width() != in.width || out->height() != in.height || out->format() != target) {
    out->resize(in.width, in.height, target);
  }
  cv::Mat dst(in.height, in.width, target == PixelFormat::kGray8 ? CV_8UC1 : CV_8UC3, out->data(),
              static_cast<size_t>(out->stride_bytes()));
  auto src = [&](int type) {
    return cv::Mat(in.height, in.width, type, const_cast<uint8_t*>(in.data),
                   static_cast<size_t>(in.stride_bytes));
  };
  switch (in.format) {
    case PixelFormat::kGray8:
      if (target == PixelFormat::kGray8) {
        src(CV_8UC1).copyTo(dst);
      } else {
        cv::cvtColor(src(CV_8UC1), dst, cv::COLOR_GRAY2RGB);
      }
      return {};
    case PixelFormat::kRgb24:
      src(CV_8UC3).copyTo(dst);
      return {};
    case PixelFormat::kBgr24:
      cv::cvtColor(src(CV_8UC3), dst, cv::COLOR_BGR2RGB);
      return {};
    case PixelFormat::kYuyv:
    case PixelFormat::kNv12:
    case PixelFormat::kYuv420:
      // Chroma interpolated as the detector does (core/pixel_read.h), so
      // that a recording of a YUV camera replays with the edges the live
      // detector saw; cv::cvtColor gives both pixels of a pair their pair's
      // chroma. Not a per-frame path of the daemon.
      for (int y = 0; y < in.height; ++y) {
        uint8_t* d = out->row(y);
        for (int x = 0; x < in.width; ++x)
          read_rgb_interpolated(in, x, y, &d[3 * x], &d[3 * x + 1], &d[3 * x + 2]);
      }
      return {};
    case PixelFormat::kMjpeg:
      break;
  }
  return make_error(std::string("to_rgb24: cannot convert ") + to_string(in.format) +
                    " (compressed frames are decoded by the source)");
}

}  // namespace ceilpose::capture
