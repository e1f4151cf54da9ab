#include "core/image.h"

namespace ceilpose {

const char* to_string(PixelFormat f) {
  switch (f) {
    case PixelFormat::kGray8:
      return "GREY";
    case PixelFormat::kRgb24:
      return "RGB24";
    case PixelFormat::kBgr24:
      return "BGR24";
    case PixelFormat::kYuyv:
      return "YUYV";
    case PixelFormat::kMjpeg:
      return "MJPEG";
    case PixelFormat::kNv12:
      return "NV12";
    case PixelFormat::kYuv420:
      return "YUV420";
  }
  return "unknown";
}

}  // namespace ceilpose
