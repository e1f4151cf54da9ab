#include "sim/camera_format.h"

#include <algorithm>
#include <cmath>

#include "core/pixel_read.h"

namespace ceilpose::sim {

namespace {

// 4:2:0 (BT.601 limited range, V4L2's default quantisation: core/pixel_read.h's
// rgb_to_y/u/v): luma per pixel, U and V of each 2x2 block's mean colour, in the
// layouts of core/image.h.
void convert_yuv420(const Image& rgb, PixelFormat format, Image& out) {
  const int w = rgb.width(), h = rgb.height();
  const ImageView view = out.view();
  for (int y = 0; y < h; ++y) {
    const uint8_t* s = rgb.data() + static_cast<size_t>(y) * rgb.stride_bytes();
    for (int x = 0; x < w; ++x) out.row(y)[x] = rgb_to_y(s[3 * x], s[3 * x + 1], s[3 * x + 2]);
  }
  for (int y = 0; y < h; y += 2) {
    for (int x = 0; x < w; x += 2) {
      double m[3] = {0, 0, 0};
      int n = 0;
      for (int yy = y; yy < std::min(y + 2, h); ++yy) {
        for (int xx = x; xx < std::min(x + 2, w); ++xx, ++n) {
          const uint8_t* p = rgb.data() + static_cast<size_t>(yy) * rgb.stride_bytes() + 3 * xx;
          for (int c = 0; c < 3; ++c) m[c] += p[c];
        }
      }
      for (double& c : m) c /= n;
      const uint8_t u = rgb_to_u(m[0], m[1], m[2]), v = rgb_to_v(m[0], m[1], m[2]);
      if (format == PixelFormat::kNv12) {
        auto* uv = const_cast<uint8_t*>(view.uv_row(y));
        uv[x] = u, uv[x + 1] = v;
      } else {
        const_cast<uint8_t*>(view.u_row(y))[x / 2] = u;
        const_cast<uint8_t*>(view.v_row(y))[x / 2] = v;
      }
    }
  }
}

}  // namespace

Image convert_rgb(const Image& rgb, PixelFormat format) {
  Image out;
  convert_rgb(rgb, format, &out);
  return out;
}

void convert_rgb(const Image& rgb, PixelFormat format, Image* out_image) {
  if (out_image->width() != rgb.width() || out_image->height() != rgb.height() ||
      out_image->format() != format)
    out_image->resize(rgb.width(), rgb.height(), format);
  Image& out = *out_image;
  if (is_yuv420(format)) return convert_yuv420(rgb, format, out);
  // One loop per format: a frame's 300 k pixels were a switch each, and a
  // 4:2:2 pair's chroma is its mean colour's, converted once (the renderer
  // must keep up with the synthetic camera's rate).
  const int w = rgb.width();
  for (int y = 0; y < rgb.height(); ++y) {
    const uint8_t* s = rgb.data() + static_cast<size_t>(y) * rgb.stride_bytes();
    uint8_t* d = out.row(y);
    switch (format) {
      case PixelFormat::kBgr24:
        for (int x = 0; x < w; ++x)
          d[3 * x] = s[3 * x + 2], d[3 * x + 1] = s[3 * x + 1], d[3 * x + 2] = s[3 * x];
        break;
      case PixelFormat::kGray8:
        for (int x = 0; x < w; ++x) d[x] = rgb_luma(s[3 * x], s[3 * x + 1], s[3 * x + 2]);
        break;
      case PixelFormat::kYuyv:
        for (int x = 0; x < w; x += 2) {
          // U and V of the pair's mean colour (the last pixel of an odd
          // width pairs with itself and has no V byte).
          const int x2 = std::min(x + 1, w - 1);
          const int r = s[3 * x], g = s[3 * x + 1], b = s[3 * x + 2];
          const double r2 = 0.5 * (r + s[3 * x2]), g2 = 0.5 * (g + s[3 * x2 + 1]),
                       b2 = 0.5 * (b + s[3 * x2 + 2]);
          uint8_t* pair = d + 2 * x;  // x is even: a pair's first byte
          pair[0] = rgb_to_y(r, g, b);
          pair[kYuyvUByte] = rgb_to_u(r2, g2, b2);
          if (x + 1 < w) {
            pair[kYuyvSecondLumaByte] = rgb_to_y(s[3 * x2], s[3 * x2 + 1], s[3 * x2 + 2]);
            pair[kYuyvVByte] = rgb_to_v(r2, g2, b2);
          }
        }
        break;
      case PixelFormat::kRgb24:
      case PixelFormat::kMjpeg:
      case PixelFormat::kNv12:
      case PixelFormat::kYuv420:
        std::copy(s, s + 3 * static_cast<size_t>(w), d);
        break;
    }
  }
}

}  // namespace ceilpose::sim
