#include "tests/pipeline/detect_scene_support.h"

#include <algorithm>
#include <cmath>

namespace ceilpose::test {
namespace {

double to_linear(double srgb8) {
  const double c = srgb8 / 255.0;
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

uint8_t to_srgb8(double linear) {
  const double l = std::clamp(linear, 0.0, 1.0);
  const double c = l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
  return static_cast<uint8_t>(std::lround(255.0 * c));
}

// Printed colour at marker-frame point (e, n); false outside the marker.
bool marker_colour(const CeilingLayout& layout, const CraftedMarker& m, double e_m, double n_m,
                   Rgb* colour) {
  if (std::abs(n_m) > 0.5 * layout.rect_height_m || std::abs(e_m) > layout.rect_width_m)
    return false;
  const bool red = e_m >= 0.0;
  const int code = red ? m.code_i : m.code_j;
  const double centre_e_m = red ? layout.red_centre_e_m() : layout.green_centre_e_m();
  const double half_e_m = 0.5 * (red ? layout.red_dot_e_m : layout.green_dot_e_m);
  const double half_n_m = 0.5 * (red ? layout.red_dot_n_m : layout.green_dot_n_m);
  for (int k = 0; k < layout.bits; ++k) {
    if (!layout.slot_bit(code, k)) continue;
    const double a = (e_m - centre_e_m) / half_e_m, b = (n_m - layout.slot_n_m(k)) / half_n_m;
    if (a * a + b * b <= 1.0) {
      *colour = layout.dot;
      return true;
    }
  }
  *colour = red ? layout.red : layout.green;
  return true;
}

}  // namespace

void put_rgb(Image* image, int x, int y, Rgb colour) {
  uint8_t* p = image->row(y) + 3 * x;
  p[0] = colour.r;
  p[1] = colour.g;
  p[2] = colour.b;
}

Image render_markers(int width_px, int height_px, std::span<const CraftedMarker> markers,
                     const CeilingLayout& layout, const Lighting& lighting, double px_per_m) {
  Image out(width_px, height_px, PixelFormat::kRgb24);
  const std::array<double, 3> tile{to_linear(layout.tile.r), to_linear(layout.tile.g),
                                   to_linear(layout.tile.b)};
  std::vector<std::array<double, 3>> linear(static_cast<size_t>(width_px) * height_px, tile);
  auto linear_of = [](Rgb c) {
    return std::array<double, 3>{to_linear(c.r), to_linear(c.g), to_linear(c.b)};
  };
  const auto red_l = linear_of(layout.red), green_l = linear_of(layout.green),
             dot_l = linear_of(layout.dot);
  const double reach_px = px_per_m * std::hypot(layout.rect_width_m, 0.5 * layout.rect_height_m);
  constexpr int kSub = 8;
  for (const CraftedMarker& m : markers) {
    const double wu = std::cos(m.west_image_rad), wv = std::sin(m.west_image_rad);
    // East = −West; North = (West_v, −West_u) in image axes (SPEC §3).
    const double eu = -wu, ev = -wv, nu = wv, nv = -wu;
    const int x0 = std::max(0, static_cast<int>(m.centre_u_px - reach_px) - 1);
    const int x1 = std::min(width_px - 1, static_cast<int>(m.centre_u_px + reach_px) + 1);
    const int y0 = std::max(0, static_cast<int>(m.centre_v_px - reach_px) - 1);
    const int y1 = std::min(height_px - 1, static_cast<int>(m.centre_v_px + reach_px) + 1);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        std::array<double, 3> sum{};
        int hits = 0;
        for (int sy = 0; sy < kSub; ++sy) {
          for (int sx = 0; sx < kSub; ++sx) {
            const double du = x - 0.5 + (sx + 0.5) / kSub - m.centre_u_px;
            const double dv = y - 0.5 + (sy + 0.5) / kSub - m.centre_v_px;
            Rgb c{};
            if (!marker_colour(layout, m, (du * eu + dv * ev) / px_per_m,
                               (du * nu + dv * nv) / px_per_m, &c))
              continue;
            const auto& l = (c.r == layout.dot.r && c.g == layout.dot.g)   ? dot_l
                            : (c.r == layout.red.r && c.g == layout.red.g) ? red_l
                                                                           : green_l;
            sum[0] += l[0];
            sum[1] += l[1];
            sum[2] += l[2];
            ++hits;
          }
        }
        if (hits == 0) continue;
        auto& px = linear[static_cast<size_t>(y) * width_px + x];
        for (int c = 0; c < 3; ++c) px[c] = (sum[c] + (kSub * kSub - hits) * px[c]) / (kSub * kSub);
      }
    }
  }
  // Most pixels are plain tile: convert each distinct value once.
  std::array<uint8_t, 3> tile_out{};
  for (int c = 0; c < 3; ++c) tile_out[c] = to_srgb8(tile[c] * lighting.gain * lighting.cast[c]);
  for (int y = 0; y < height_px; ++y) {
    for (int x = 0; x < width_px; ++x) {
      const auto& px = linear[static_cast<size_t>(y) * width_px + x];
      uint8_t* p = out.row(y) + 3 * x;
      for (int c = 0; c < 3; ++c)
        p[c] = px == tile ? tile_out[c] : to_srgb8(px[c] * lighting.gain * lighting.cast[c]);
    }
  }
  return out;
}

Image blur_rows(const Image& rgb, int length_px) {
  Image out = rgb;
  for (int y = 0; y < rgb.height(); ++y) {
    const uint8_t* s = rgb.data() + static_cast<size_t>(y) * rgb.stride_bytes();
    for (int x = 0; x < rgb.width(); ++x) {
      for (int c = 0; c < 3; ++c) {
        int sum = 0;
        for (int k = -length_px / 2; k <= length_px / 2; ++k)
          sum += s[3 * std::clamp(x + k, 0, rgb.width() - 1) + c];
        out.row(y)[3 * x + c] = static_cast<uint8_t>(sum / (2 * (length_px / 2) + 1));
      }
    }
  }
  return out;
}

// The default camera scaled: pixel centres map to pixel centres.
CameraIntrinsics scaled_default_camera(double scale) {
  CameraIntrinsics k;
  k.width = static_cast<int>(k.width * scale);
  k.height = static_cast<int>(k.height * scale);
  k.fx *= scale;
  k.fy *= scale;
  k.cx = (k.cx + 0.5) * scale - 0.5;
  k.cy = (k.cy + 0.5) * scale - 0.5;
  return k;
}

CameraIntrinsics half_size_camera() { return scaled_default_camera(0.5); }

CameraIntrinsics double_size_camera() { return scaled_default_camera(2.0); }

}  // namespace ceilpose::test
