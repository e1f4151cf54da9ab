#pragma once
// One pixel's colour in any uncompressed camera format (core/image.h), for
// sparse reads (the classifier's white sample, dot slots) and conversions
// that are not per frame. A pixel gets its pair's chroma, which is right
// inside a uniform area (tile, dot slot); the detector's sweeps, which must
// place coloured edges, interpolate chroma between pairs instead
// (pipeline/components.cpp).
#include <algorithm>
#include <cstdint>

#include "core/image.h"

namespace ceilpose {

// BT.601 limited range (V4L2's default quantisation for YUYV) to RGB, integer.
inline void yuv_to_rgb(int y, int u, int v, uint8_t* r, uint8_t* g, uint8_t* b) {
  const int c = 298 * (y - 16) + 128;
  const int d = u - 128, e = v - 128;
  *r = static_cast<uint8_t>(std::clamp((c + 409 * e) >> 8, 0, 255));
  *g = static_cast<uint8_t>(std::clamp((c - 100 * d - 208 * e) >> 8, 0, 255));
  *b = static_cast<uint8_t>(std::clamp((c + 516 * d) >> 8, 0, 255));
}

// RGB of pixel (x, y) in any uncompressed format; grey gives r = g = b.
// For sparse reads only (white sample, dot slots), not for full-frame sweeps.
inline void read_rgb(const ImageView& f, int x, int y, uint8_t* r, uint8_t* g, uint8_t* b) {
  const uint8_t* p = f.row(y);
  switch (f.format) {
    case PixelFormat::kRgb24:
      *r = p[3 * x], *g = p[3 * x + 1], *b = p[3 * x + 2];
      return;
    case PixelFormat::kBgr24:
      *b = p[3 * x], *g = p[3 * x + 1], *r = p[3 * x + 2];
      return;
    case PixelFormat::kYuyv: {
      const uint8_t* q = p + 4 * (x / 2);
      yuv_to_rgb(q[(x & 1) * 2], q[1], q[3], r, g, b);
      return;
    }
    case PixelFormat::kNv12: {
      const uint8_t* uv = f.uv_row(y) + (x & ~1);
      yuv_to_rgb(p[x], uv[0], uv[1], r, g, b);
      return;
    }
    case PixelFormat::kYuv420:
      yuv_to_rgb(p[x], f.u_row(y)[x / 2], f.v_row(y)[x / 2], r, g, b);
      return;
    case PixelFormat::kGray8:
      *r = *g = *b = p[x];
      return;
    case PixelFormat::kMjpeg:
      break;
  }
  *r = *g = *b = 0;
}

}  // namespace ceilpose
