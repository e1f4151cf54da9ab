#pragma once
// One pixel's colour in any uncompressed camera format (core/image.h), for
// sparse reads (the classifier's white sample, dot slots) and conversions
// that are not per frame. A pixel gets its pair's chroma, which is right
// inside a uniform area (tile, dot slot); the detector's sweeps, which must
// place coloured edges, interpolate chroma between pairs instead
// (pipeline/components.cpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "core/image.h"

namespace ceilpose {

// BT.601 limited range (V4L2's default quantisation for YUYV) to RGB,
// integer: channel = clamp((luma part + the channel's chroma part) >> 8).
constexpr int yuv_luma_part(int y) { return 298 * (y - 16) + 128; }
struct YuvChromaParts {
  int r, g, b;
};
constexpr YuvChromaParts yuv_chroma_parts(int u, int v) {
  const int d = u - 128, e = v - 128;
  return {409 * e, -100 * d - 208 * e, 516 * d};
}
inline uint8_t yuv_channel(int luma_part, int chroma_part) {
  return static_cast<uint8_t>(std::clamp((luma_part + chroma_part) >> 8, 0, 255));
}
inline void yuv_to_rgb(int y, int u, int v, uint8_t* r, uint8_t* g, uint8_t* b) {
  const int c = yuv_luma_part(y);
  const YuvChromaParts p = yuv_chroma_parts(u, v);
  *r = yuv_channel(c, p.r);
  *g = yuv_channel(c, p.g);
  *b = yuv_channel(c, p.b);
}
// RGB levels (0..255, fractional allowed) to BT.601 limited range, rounded:
// yuv_to_rgb's inverse up to rounding. A simulated camera's conversion, and
// where the classifier looks for the tile in a camera's bytes.
struct Yuv {
  uint8_t y, u, v;
};
// Each component alone as well (a camera's 4:2:2 pair has two lumas and one
// chroma): rgb_to_yuv is the three together.
inline uint8_t yuv_byte(double x) {
  // std::lround's rounding (halves away from zero) without its library call:
  // c - whole is exact for c in [0, 255]. A NaN passes std::clamp unchanged
  // and would make the cast undefined, so it is sent to 0 first.
  if (!(x > 0.0)) return 0;
  const double c = std::min(x, 255.0);
  const int whole = static_cast<int>(c);
  return static_cast<uint8_t>(whole + (c - whole >= 0.5 ? 1 : 0));
}
inline uint8_t rgb_to_y(double r, double g, double b) {
  return yuv_byte(16.0 + (65.481 * r + 128.553 * g + 24.966 * b) / 255.0);
}
inline uint8_t rgb_to_u(double r, double g, double b) {
  return yuv_byte(128.0 + (-37.797 * r - 74.203 * g + 112.0 * b) / 255.0);
}
inline uint8_t rgb_to_v(double r, double g, double b) {
  return yuv_byte(128.0 + (112.0 * r - 93.786 * g - 18.214 * b) / 255.0);
}
inline Yuv rgb_to_yuv(double r, double g, double b) {
  return {rgb_to_y(r, g, b), rgb_to_u(r, g, b), rgb_to_v(r, g, b)};
}

// The darkest of the three channels yuv_to_rgb gives, without the three: a
// channel rises with its chroma part (clamp and shift keep order), so the
// darkest is the one with the least.
inline uint8_t yuv_darkest(int y, int u, int v) {
  const YuvChromaParts p = yuv_chroma_parts(u, v);
  return yuv_channel(yuv_luma_part(y), std::min({p.r, p.g, p.b}));
}

// RGB of pixel (x, y) of a frame in format F (not MJPEG); grey gives
// r = g = b. The one formula per format that read_rgb and read_rgb_2x2 share.
template <PixelFormat F>
inline Rgb pixel_rgb(const ImageView& f, int x, int y) {
  const uint8_t* p = f.row(y);
  Rgb c{0, 0, 0};
  if constexpr (F == PixelFormat::kRgb24) {
    c = {p[3 * x], p[3 * x + 1], p[3 * x + 2]};
  } else if constexpr (F == PixelFormat::kBgr24) {
    c = {p[3 * x + 2], p[3 * x + 1], p[3 * x]};
  } else if constexpr (F == PixelFormat::kYuyv) {
    const uint8_t* q = p + kYuyvPairBytes * (x / 2);
    yuv_to_rgb(p[2 * x], q[kYuyvUByte], q[kYuyvVByte], &c.r, &c.g, &c.b);
  } else if constexpr (F == PixelFormat::kNv12) {
    const uint8_t* uv = f.uv_row(y) + (x & ~1);
    yuv_to_rgb(p[x], uv[0], uv[1], &c.r, &c.g, &c.b);
  } else if constexpr (F == PixelFormat::kYuv420) {
    yuv_to_rgb(p[x], f.u_row(y)[x / 2], f.v_row(y)[x / 2], &c.r, &c.g, &c.b);
  } else if constexpr (F == PixelFormat::kGray8) {
    c = {p[x], p[x], p[x]};
  }
  return c;
}

// The darkest channel of pixel_rgb<F>(f, x, y), as std::min of its three.
template <PixelFormat F>
inline uint8_t pixel_darkest(const ImageView& f, int x, int y) {
  const uint8_t* p = f.row(y);
  if constexpr (F == PixelFormat::kYuyv) {
    const uint8_t* q = p + kYuyvPairBytes * (x / 2);
    return yuv_darkest(p[2 * x], q[kYuyvUByte], q[kYuyvVByte]);
  } else if constexpr (F == PixelFormat::kNv12) {
    const uint8_t* uv = f.uv_row(y) + (x & ~1);
    return yuv_darkest(p[x], uv[0], uv[1]);
  } else if constexpr (F == PixelFormat::kYuv420) {
    return yuv_darkest(p[x], f.u_row(y)[x / 2], f.v_row(y)[x / 2]);
  } else {
    const Rgb c = pixel_rgb<F>(f, x, y);
    return std::min({c.r, c.g, c.b});
  }
}

// Which channel a rectangle's edge is measured in (pipeline/rectangle_ends.h):
// the one it prints dark in, the same on both sides of the edge; or the
// luma, where the colour channels carry chroma at half the resolution.
enum class EdgeChannel : uint8_t { kRed, kGreen, kLuma };

// BT.601 luma of 8-bit R, G, B.
inline uint8_t rgb_luma(int r, int g, int b) {
  return static_cast<uint8_t>((77 * r + 150 * g + 29 * b + 128) >> 8);
}

// That channel's level at pixel (x, y) of a frame in format F (not MJPEG).
// YUV formats always give their luma, full range: their chroma has half the
// resolution, which would blur and shift an edge. Grey gives its level.
template <PixelFormat F>
inline uint8_t pixel_edge_level(const ImageView& f, int x, int y, EdgeChannel channel) {
  const uint8_t* p = f.row(y);
  const int rgb_offset = channel == EdgeChannel::kRed ? 0 : 1;
  if constexpr (F == PixelFormat::kRgb24) {
    const uint8_t* q = p + 3 * x;
    return channel == EdgeChannel::kLuma ? rgb_luma(q[0], q[1], q[2]) : q[rgb_offset];
  } else if constexpr (F == PixelFormat::kBgr24) {
    const uint8_t* q = p + 3 * x;
    return channel == EdgeChannel::kLuma ? rgb_luma(q[2], q[1], q[0]) : q[2 - rgb_offset];
  } else if constexpr (F == PixelFormat::kYuyv) {
    return yuv_channel(yuv_luma_part(p[2 * x]), 0);
  } else if constexpr (F == PixelFormat::kNv12 || F == PixelFormat::kYuv420) {
    return yuv_channel(yuv_luma_part(p[x]), 0);
  } else {
    return p[x];
  }
}

// Calls fn(std::integral_constant<PixelFormat, F>) for the frame's format F;
// false for MJPEG (no pixels to read). One dispatch for a caller's many
// reads.
template <typename Fn>
inline bool with_pixel_format(PixelFormat format, Fn&& fn) {
  switch (format) {
    case PixelFormat::kRgb24:
      fn(std::integral_constant<PixelFormat, PixelFormat::kRgb24>{});
      return true;
    case PixelFormat::kBgr24:
      fn(std::integral_constant<PixelFormat, PixelFormat::kBgr24>{});
      return true;
    case PixelFormat::kYuyv:
      fn(std::integral_constant<PixelFormat, PixelFormat::kYuyv>{});
      return true;
    case PixelFormat::kNv12:
      fn(std::integral_constant<PixelFormat, PixelFormat::kNv12>{});
      return true;
    case PixelFormat::kYuv420:
      fn(std::integral_constant<PixelFormat, PixelFormat::kYuv420>{});
      return true;
    case PixelFormat::kGray8:
      fn(std::integral_constant<PixelFormat, PixelFormat::kGray8>{});
      return true;
    case PixelFormat::kMjpeg:
      break;
  }
  return false;
}

// Calls fn(pixel_rgb<F>) for the frame's format F; false for MJPEG.
template <typename Fn>
inline bool with_pixel_reader(PixelFormat format, Fn&& fn) {
  return with_pixel_format(format, [&](auto tag) { fn(pixel_rgb<decltype(tag)::value>); });
}

// RGB of pixel (x, y) in any uncompressed format; grey gives r = g = b.
// For sparse reads only (white sample, dot slots), not for full-frame sweeps.
inline void read_rgb(const ImageView& f, int x, int y, uint8_t* r, uint8_t* g, uint8_t* b) {
  Rgb c{0, 0, 0};
  with_pixel_reader(f.format, [&](auto read) { c = read(f, x, y); });
  *r = c.r, *g = c.g, *b = c.b;
}

// Pixels (x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1), in that order, each
// as read_rgb gives it, with one dispatch on the format for the four: a
// bilinear sample needs them, and dot slots and rectangle edges take
// thousands of samples a frame.
inline void read_rgb_2x2(const ImageView& f, int x, int y, std::array<Rgb, 4>* out) {
  out->fill(Rgb{0, 0, 0});
  with_pixel_reader(f.format, [&](auto read) {
    for (int k = 0; k < 4; ++k) (*out)[k] = read(f, x + (k & 1), y + (k >> 1));
  });
}

// The same four pixels' darkest channels (pixel_darkest); 0 for MJPEG.
inline void read_darkest_2x2(const ImageView& f, int x, int y, std::array<uint8_t, 4>* out) {
  out->fill(0);
  with_pixel_format(f.format, [&](auto tag) {
    for (int k = 0; k < 4; ++k)
      (*out)[k] = pixel_darkest<decltype(tag)::value>(f, x + (k & 1), y + (k >> 1));
  });
}

// Chroma is sampled once per pixel pair (and per row pair in 4:2:0),
// sited at the pair's centre (V4L2's sample locations). Interpolated at a
// pixel, pixel 2p lies a quarter of the way from its pair's sample to pair
// p-1's, pixel 2p+1 to pair p+1's (weights 3:1); 4:2:0 rows likewise. Giving
// both pixels their pair's chroma instead snaps every coloured edge to a
// pair boundary, and marker centroids with it. The detector's sweeps inline
// the same rule (pipeline/components.cpp).
inline constexpr int kChromaOwnWeight = 3;
inline constexpr int kChromaNeighbourWeight = 1;
// The pair whose chroma pixel x leans towards, within a row of width_px.
inline int chroma_neighbour_pair(int x, int width_px) {
  const int pair = x >> 1;
  return (x & 1) == 0 ? std::max(pair - 1, 0) : std::min(pair + 1, (width_px - 1) >> 1);
}
// A luma row whose chroma row is the one row y leans towards (4:2:0).
inline int chroma_neighbour_row(int y, int height_px) {
  return (y & 1) == 0 ? std::max(y - 2, 0) : std::min(y + 2, height_px - 1);
}

// RGB of pixel (x, y) with chroma interpolated as above (YUV formats; the
// others as read_rgb). For conversions that are not per frame in the daemon
// (recordings of YUV cameras), so that they keep the edges the detector sees.
inline void read_rgb_interpolated(const ImageView& f, int x, int y, uint8_t* r, uint8_t* g,
                                  uint8_t* b) {
  if (f.format != PixelFormat::kYuyv && !is_yuv420(f.format)) return read_rgb(f, x, y, r, g, b);
  const int own = x >> 1, other = chroma_neighbour_pair(x, f.width);
  int u4[2] = {0, 0}, v4[2] = {0, 0};  // own pair, neighbour pair; x4 (4:2:0: rows blended)
  int luma = 0;
  if (f.format == PixelFormat::kYuyv) {
    const uint8_t* p = f.row(y);
    luma = p[2 * x];
    for (int k = 0; k < 2; ++k) {
      const int pair = k == 0 ? own : other;
      const uint8_t* q = p + kYuyvPairBytes * pair;
      u4[k] = 4 * q[kYuyvUByte], v4[k] = 4 * q[kYuyvVByte];
    }
  } else {
    luma = f.row(y)[x];
    const int y_other = chroma_neighbour_row(y, f.height);
    for (int k = 0; k < 2; ++k) {
      const int pair = k == 0 ? own : other;
      int u_near = 0, v_near = 0, u_far = 0, v_far = 0;
      if (f.format == PixelFormat::kNv12) {
        u_near = f.uv_row(y)[2 * pair], v_near = f.uv_row(y)[2 * pair + 1];
        u_far = f.uv_row(y_other)[2 * pair], v_far = f.uv_row(y_other)[2 * pair + 1];
      } else {
        u_near = f.u_row(y)[pair], v_near = f.v_row(y)[pair];
        u_far = f.u_row(y_other)[pair], v_far = f.v_row(y_other)[pair];
      }
      u4[k] = kChromaOwnWeight * u_near + kChromaNeighbourWeight * u_far;
      v4[k] = kChromaOwnWeight * v_near + kChromaNeighbourWeight * v_far;
    }
  }
  // Weights sum to 4 in each direction: u16 / 16 with rounding.
  const int u16 = kChromaOwnWeight * u4[0] + kChromaNeighbourWeight * u4[1];
  const int v16 = kChromaOwnWeight * v4[0] + kChromaNeighbourWeight * v4[1];
  yuv_to_rgb(luma, (u16 + 8) >> 4, (v16 + 8) >> 4, r, g, b);
}

// Asks the memory system for bytes [begin, end) ahead of their use (a hint:
// no effect on results, a no-op where the CPU has no prefetch): each cache
// line they touch, once.
inline void prefetch_bytes(const uint8_t* begin, const uint8_t* end) {
  constexpr uintptr_t kLineBytes = 64;
  const uintptr_t last = reinterpret_cast<uintptr_t>(end);
  for (uintptr_t a = reinterpret_cast<uintptr_t>(begin) & ~(kLineBytes - 1); a < last;
       a += kLineBytes)
    __builtin_prefetch(reinterpret_cast<const void*>(a));
  // GCC counts a prefetch as no effect at all, finds a function of nothing
  // else "const" and drops its calls (seen: no prefetch left in the
  // object). A volatile asm is an effect it keeps, and unlike a compiler
  // memory barrier it leaves the caller's values in registers (a tracked
  // frame asks for ~1300 rows).
  asm volatile("");
}

// The same for pixels x0..x1 (x0 >= 0) of row y, every plane of format F.
template <PixelFormat F>
inline void prefetch_pixels(const ImageView& f, int y, int x0, int x1) {
  const uint8_t* p = f.row(y);
  if constexpr (F == PixelFormat::kRgb24 || F == PixelFormat::kBgr24) {
    prefetch_bytes(p + 3 * x0, p + 3 * (x1 + 1));
  } else if constexpr (F == PixelFormat::kYuyv) {
    prefetch_bytes(p + kYuyvPairBytes * (x0 >> 1), p + kYuyvPairBytes * ((x1 >> 1) + 1));
  } else if constexpr (F == PixelFormat::kNv12) {
    prefetch_bytes(p + x0, p + x1 + 1);
    prefetch_bytes(f.uv_row(y) + (x0 & ~1), f.uv_row(y) + (x1 | 1) + 1);
  } else if constexpr (F == PixelFormat::kYuv420) {
    prefetch_bytes(p + x0, p + x1 + 1);
    prefetch_bytes(f.u_row(y) + (x0 >> 1), f.u_row(y) + (x1 >> 1) + 1);
    prefetch_bytes(f.v_row(y) + (x0 >> 1), f.v_row(y) + (x1 >> 1) + 1);
  } else {
    prefetch_bytes(p + x0, p + x1 + 1);
  }
}

inline void prefetch_pixels(const ImageView& f, int y, int x0, int x1) {
  with_pixel_format(f.format,
                    [&](auto tag) { prefetch_pixels<decltype(tag)::value>(f, y, x0, x1); });
}

}  // namespace ceilpose
