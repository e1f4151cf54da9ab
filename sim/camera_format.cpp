#include "sim/camera_format.h"

#include <algorithm>
#include <cmath>

#include "core/pixel_read.h"

namespace ceilpose::sim {

namespace {

// BT.601 limited range, V4L2's default quantisation (core/pixel_read.h).
uint8_t luma(double r, double g, double b) { return rgb_to_yuv(r, g, b).y; }
uint8_t chroma_u(double r, double g, double b) { return rgb_to_yuv(r, g, b).u; }
uint8_t chroma_v(double r, double g, double b) { return rgb_to_yuv(r, g, b).v; }

// 4:2:0: luma per pixel, U and V of each 2x2 block's mean colour, in the
// layouts of core/image.h.
void convert_yuv420(const Image& rgb, PixelFormat format, Image& out) {
  const int w = rgb.width(), h = rgb.height();
  const ImageView view = out.view();
  for (int y = 0; y < h; ++y) {
    const uint8_t* s = rgb.data() + static_cast<size_t>(y) * rgb.stride_bytes();
    for (int x = 0; x < w; ++x) out.row(y)[x] = luma(s[3 * x], s[3 * x + 1], s[3 * x + 2]);
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
      const uint8_t u = chroma_u(m[0], m[1], m[2]), v = chroma_v(m[0], m[1], m[2]);
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
          // U and V from this pixel and its pair.
          d[2 * x] = luma(r, g, b);
          if ((x & 1) == 0) {
            const int x2 = std::min(x + 1, rgb.width() - 1);
            const double r2 = 0.5 * (r + s[3 * x2]), g2 = 0.5 * (g + s[3 * x2 + 1]),
                         b2 = 0.5 * (b + s[3 * x2 + 2]);
            d[2 * x + 1] = chroma_u(r2, g2, b2);
            if (x + 1 < rgb.width()) d[2 * x + 3] = chroma_v(r2, g2, b2);
          }
          break;
        }
        case PixelFormat::kRgb24:
        case PixelFormat::kMjpeg:
        case PixelFormat::kNv12:
        case PixelFormat::kYuv420:
          d[3 * x] = s[3 * x], d[3 * x + 1] = s[3 * x + 1], d[3 * x + 2] = s[3 * x + 2];
          break;
      }
    }
  }
}

}  // namespace ceilpose::sim
