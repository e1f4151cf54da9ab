#include "sim/camera_format.h"

#include <algorithm>
#include <cmath>

namespace ceilpose::sim {

Image convert_rgb(const Image& rgb, PixelFormat format) {
  Image out(rgb.width(), rgb.height(), format);
  for (int y = 0; y < rgb.height(); ++y) {
    const uint8_t* s = rgb.data() + static_cast<size_t>(y) * rgb.stride_bytes();
    uint8_t* d = out.row(y);
    for (int x = 0; x < rgb.width(); ++x) {
      const int r = s[3 * x], g = s[3 * x + 1], b = s[3 * x + 2];
      switch (format) {
        case PixelFormat::kBgr24:
          d[3 * x] = static_cast<uint8_t>(b);
          d[3 * x + 1] = static_cast<uint8_t>(g);
          d[3 * x + 2] = static_cast<uint8_t>(r);
          break;
        case PixelFormat::kGray8:
          d[x] = static_cast<uint8_t>((77 * r + 150 * g + 29 * b + 128) >> 8);
          break;
        case PixelFormat::kYuyv: {
          // BT.601 limited range; U and V from this pixel and its pair.
          const double yl = 16.0 + (65.481 * r + 128.553 * g + 24.966 * b) / 255.0;
          d[2 * x] = static_cast<uint8_t>(std::lround(yl));
          if ((x & 1) == 0) {
            const int x2 = std::min(x + 1, rgb.width() - 1);
            const double r2 = 0.5 * (r + s[3 * x2]), g2 = 0.5 * (g + s[3 * x2 + 1]),
                         b2 = 0.5 * (b + s[3 * x2 + 2]);
            const double u = 128.0 + (-37.797 * r2 - 74.203 * g2 + 112.0 * b2) / 255.0;
            const double v = 128.0 + (112.0 * r2 - 93.786 * g2 - 18.214 * b2) / 255.0;
            d[2 * x + 1] = static_cast<uint8_t>(std::lround(std::clamp(u, 0.0, 255.0)));
            if (x + 1 < rgb.width())
              d[2 * x + 3] = static_cast<uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
          }
          break;
        }
        case PixelFormat::kRgb24:
        case PixelFormat::kMjpeg:
          d[3 * x] = s[3 * x], d[3 * x + 1] = s[3 * x + 1], d[3 * x + 2] = s[3 * x + 2];
          break;
      }
    }
  }
  return out;
}

}  // namespace ceilpose::sim
