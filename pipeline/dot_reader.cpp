#include "pipeline/dot_reader.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

#include "core/int_rounding.h"
#include "core/length_2d.h"
#include "core/pixel_read.h"
#include "pipeline/color_classifier.h"

// Heading (SPEC §2–3). The red→green vector is the marker's West. Looking
// up, the image is the ceiling seen from below, so with West at image
// direction (a, b) North is at (b, −a) and East at (−a, −b): at yaw 0, West
// is image down (0, 1) and North image right (1, 0), as SPEC §3's camera axes
// give. The scale comes from the long sides (12 in), which thresholding
// shortens least in relative terms.
//
// Read_Dots. A slot holds a dot when its brightness, sampled bilinearly on
// the dot's core, falls below a threshold ratio (raised with blur) of the
// rectangle's own
// brightness, measured the same way half-way between slots where no dot is
// ever printed. Brightness is taken both as the brightest channel and as
// luma, and the lower ratio counts (see brightness_at). A ratio of
// two readings of the same frame is independent of exposure; a printed dot
// reads ≈ 0.13–0.16 of its rectangle when sharp, and ≈ 0.5 only under blur
// that would also hide the marker.

namespace ceilpose {
namespace {

// Two brightness measures at an image point, bilinear between pixels:
// [0] the brightest channel, where a dot contrasts most with its colour
// (25 against 200 or 160), and [1] luma, which YUYV and JPEG keep at full
// resolution when they halve the chroma that carries most of a red dot's
// contrast. {−1, −1} outside the frame.
using Brightness = std::array<double, 2>;

// Each channel's share of luma by level, the same products 0.299 r,
// 0.587 g, 0.114 b: three loads instead of three conversions and
// multiplications, for every pixel of ~800 samples a tracked frame.
const std::array<std::array<double, 256>, 3>& luma_shares() {
  static const auto table = [] {
    std::array<std::array<double, 256>, 3> t{};
    for (int i = 0; i < 256; ++i) {
      t[0][static_cast<size_t>(i)] = 0.299 * i;
      t[1][static_cast<size_t>(i)] = 0.587 * i;
      t[2][static_cast<size_t>(i)] = 0.114 * i;
    }
    return t;
  }();
  return table;
}

// Adds weight w of both measures of a pixel of levels (r, g, b).
void add_measures(uint8_t r, uint8_t g, uint8_t b, double w, Brightness* out) {
  const auto& share = luma_shares();
  (*out)[0] += w * std::max({r, g, b});
  (*out)[1] += w * (share[0][r] + share[1][g] + share[2][b]);
}

// A YUV pixel's channel before yuv_channel's clamp, (luma part + chroma
// part) >> 8, lies in [kUnclampedMin, kUnclampedMax] for any bytes (the
// parts' extremes, asserted below). Tables of it hold the clamp: each
// channel's share of luma at its clamped level, and the clamped level. A
// pixel's brightest channel is the one of the largest unclamped level
// (shift and clamp keep order): one clamp a pixel, by table, instead of
// three and a maximum.
constexpr int kUnclampedMin = -277, kUnclampedMax = 534;
constexpr int unclamped_extreme(bool highest) {
  const int luma = highest ? yuv_luma_part(255) : yuv_luma_part(0);
  int chroma = 0;
  for (int u : {0, 255}) {
    for (int v : {0, 255}) {
      const YuvChromaParts p = yuv_chroma_parts(u, v);
      for (int c : {p.r, p.g, p.b}) chroma = highest ? std::max(chroma, c) : std::min(chroma, c);
    }
  }
  return (luma + chroma) >> 8;
}
static_assert(unclamped_extreme(false) == kUnclampedMin &&
              unclamped_extreme(true) == kUnclampedMax);
constexpr size_t kUnclampedLevels = kUnclampedMax - kUnclampedMin + 1;
struct UnclampedTables {
  std::array<std::array<double, kUnclampedLevels>, 3> share;
  std::array<double, kUnclampedLevels> level;
};
const UnclampedTables& unclamped_tables() {
  static const UnclampedTables tables = [] {
    UnclampedTables t{};
    for (int i = kUnclampedMin; i <= kUnclampedMax; ++i) {
      const size_t k = static_cast<size_t>(i - kUnclampedMin);
      const auto level = static_cast<size_t>(std::clamp(i, 0, 255));
      for (size_t c = 0; c < 3; ++c) t.share[c][k] = luma_shares()[c][level];
      t.level[k] = static_cast<double>(level);
    }
    return t;
  }();
  return tables;
}

// The same sum over a YUYV frame's pixels (x0, y0) to (x0 + 1, y0 + 1), in
// the same order, each pixel's levels as pixel_rgb gives them: a row's two
// pixels share one chroma pair when x0 is even, so its parts are computed
// once: 336 → 298 instructions a sample (640×480 YUYV drive, ~650 samples a
// frame).
Brightness yuyv_brightness(const ImageView& frame, int x0, int y0, const double (&w)[4]) {
  Brightness out{0.0, 0.0};
  const int pair = x0 >> 1;
  const UnclampedTables& t = unclamped_tables();
  auto add = [&](int y_level, const YuvChromaParts& p, double weight) {
    const int luma = yuv_luma_part(y_level);
    const auto r = static_cast<size_t>(((luma + p.r) >> 8) - kUnclampedMin);
    const auto g = static_cast<size_t>(((luma + p.g) >> 8) - kUnclampedMin);
    const auto b = static_cast<size_t>(((luma + p.b) >> 8) - kUnclampedMin);
    out[0] += weight * t.level[std::max({r, g, b})];
    out[1] += weight * (t.share[0][r] + t.share[1][g] + t.share[2][b]);
  };
  for (int row = 0; row < 2; ++row) {
    const uint8_t* q = frame.row(y0 + row) + kYuyvPairBytes * pair;
    const uint8_t* next = q + kYuyvPairBytes;
    const YuvChromaParts own = yuv_chroma_parts(q[kYuyvUByte], q[kYuyvVByte]);
    if ((x0 & 1) == 0) {
      add(q[0], own, w[2 * row]);
      add(q[kYuyvSecondLumaByte], own, w[2 * row + 1]);
    } else {
      add(q[kYuyvSecondLumaByte], own, w[2 * row]);
      add(next[0], yuv_chroma_parts(next[kYuyvUByte], next[kYuyvVByte]), w[2 * row + 1]);
    }
  }
  return out;
}

Brightness brightness_at(const ImageView& frame, double u, double v) {
  const int x0 = floor_int(u), y0 = floor_int(v);
  if (x0 < 0 || y0 < 0 || x0 + 1 >= frame.width || y0 + 1 >= frame.height) return {-1.0, -1.0};
  const double fu = u - x0, fv = v - y0;
  const double w[4] = {(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv};
  if (frame.format == PixelFormat::kYuyv) return yuyv_brightness(frame, x0, y0, w);
  Brightness out{0.0, 0.0};
  std::array<Rgb, 4> px;
  read_rgb_2x2(frame, x0, y0, &px);
  for (int k = 0; k < 4; ++k) add_measures(px[k].r, px[k].g, px[k].b, w[k], &out);
  return out;
}

// Mean brightness over a 3 × 3 grid of points around marker point (e, n),
// spread ±(spread_e_m, spread_n_m). Negative when a point is outside.
Brightness patch_brightness(const ImageView& frame, const MarkerFrame& m, double e_m, double n_m,
                            double spread_e_m, double spread_n_m) {
  Brightness sum{0.0, 0.0};
  for (int ie = -1; ie <= 1; ++ie) {
    for (int in = -1; in <= 1; ++in) {
      double u = 0.0, v = 0.0;
      m.project(e_m + ie * spread_e_m, n_m + in * spread_n_m, &u, &v);
      const Brightness b = brightness_at(frame, u, v);
      if (b[0] < 0.0) return {-1.0, -1.0};
      sum[0] += b[0] / 9.0;
      sum[1] += b[1] / 9.0;
    }
  }
  return sum;
}

// Mean brightness of three points across a slot: (e − spread, n), (e, n),
// (e + spread, n). Negative when a point is outside.
Brightness line_brightness(const ImageView& frame, const MarkerFrame& m, double e_m, double n_m,
                           double spread_e_m) {
  Brightness sum{0.0, 0.0};
  for (int ie = -1; ie <= 1; ++ie) {
    double u = 0.0, v = 0.0;
    m.project(e_m + ie * spread_e_m, n_m, &u, &v);
    const Brightness b = brightness_at(frame, u, v);
    if (b[0] < 0.0) return {-1.0, -1.0};
    sum[0] += b[0] / 3.0;
    sum[1] += b[1] / 3.0;
  }
  return sum;
}

// The reference patches: half-way between slots (and beyond the end slots
// while that stays 1 in inside the rectangle), each spread over ±a quarter
// of the rectangle's width and ±kReferenceSpreadN of a dot's height.
double reference_limit_n_m(const CeilingLayout& layout) {
  return 0.5 * layout.rect_height_m - kInch_m;
}
double reference_spread_e_m(const CeilingLayout& layout) { return 0.25 * layout.rect_width_m; }
constexpr double kReferenceSpreadN = 0.1;
// How far along North a marker frame its edges placed has its dots sought
// from their slots.
constexpr double kEdgePlacedDotSearch_m = 0.25 * kInch_m;

}  // namespace

MarkerRegion::MarkerRegion(const MarkerFrame& marker, double e0_m, double e1_m, double n0_m,
                           double n1_m, int width, int height)
    : centre_u_px_(marker.centre_u_px), centre_v_px_(marker.centre_v_px), width_(width) {
  const double det = marker.east_u * marker.north_v - marker.east_v * marker.north_u;
  const double px_per_m = length_2d(marker.north_u, marker.north_v);
  if (!(std::abs(det) > 0.0) || !(px_per_m > 0.0) || !(e0_m <= e1_m) || !(n0_m <= n1_m)) return;
  // A bilinear read at the rectangle's rim touches the pixel beyond it.
  const double pad_m = 1.5 / px_per_m;
  e0_m -= pad_m, e1_m += pad_m, n0_m -= pad_m, n1_m += pad_m;
  // (e, n) of image offset (du, dv) from the centre: the marker frame's
  // inverse.
  const double e_per_du = marker.north_v / det, e_per_dv = -marker.north_u / det;
  const double n_per_du = -marker.east_v / det, n_per_dv = marker.east_u / det;
  // Along a row, a coordinate at m_per_dv·dv + m_per_du·du lies within
  // [lo_m, hi_m] for du between (lo_m − m_per_dv·dv)/m_per_du and
  // (hi_m − m_per_dv·dv)/m_per_du, in the order of m_per_du's sign.
  auto bound = [](double m_per_dv, double m_per_du, double lo_m, double hi_m) {
    Bound b;
    if (m_per_du == 0.0) return b;
    const double px_per_m = 1.0 / m_per_du;
    b.lo_px = (m_per_du > 0.0 ? lo_m : hi_m) * px_per_m;
    b.hi_px = (m_per_du > 0.0 ? hi_m : lo_m) * px_per_m;
    b.slope = -m_per_dv * px_per_m;
    return b;
  };
  bounds_[0] = bound(e_per_dv, e_per_du, e0_m, e1_m);
  bounds_[1] = bound(n_per_dv, n_per_du, n0_m, n1_m);
  double v_min = INFINITY, v_max = -INFINITY;
  for (double e_m : {e0_m, e1_m}) {
    for (double n_m : {n0_m, n1_m}) {
      double u = 0.0, v = 0.0;
      marker.project(e_m, n_m, &u, &v);
      v_min = std::min(v_min, v);
      v_max = std::max(v_max, v);
    }
  }
  if (!std::isfinite(v_min) || !std::isfinite(v_max)) return;
  first_row_ = static_cast<int>(std::max(0.0, std::floor(v_min)));
  last_row_ = static_cast<int>(std::min(height - 1.0, std::ceil(v_max)));
}

void ask_marker_region(const ImageView& frame, const MarkerFrame& marker, double e0_m, double e1_m,
                       double n0_m, double n1_m) {
  const MarkerRegion region(marker, e0_m, e1_m, n0_m, n1_m, frame.width, frame.height);
  // One format dispatch for the region's ~130 rows (640x480).
  with_pixel_format(frame.format, [&](auto tag) {
    region.for_each_span(
        [&](int y, int x0, int x1) { prefetch_pixels<decltype(tag)::value>(frame, y, x0, x1); });
  });
}

MarkerFrame marker_frame(const RectangleCandidate& red, const RectangleCandidate& green,
                         const CeilingLayout& layout) {
  MarkerFrame m;
  m.centre_u_px = 0.5 * (red.cx + green.cx);
  m.centre_v_px = 0.5 * (red.cy + green.cy);
  // West is perpendicular to the long axes, on the green side. The axes,
  // measured along 12 in edges, fix the direction about ten times better
  // than the 5 in red→green baseline, which only gives the sign.
  const double c2 =
      red.area_px * std::cos(2.0 * red.axis_rad) + green.area_px * std::cos(2.0 * green.axis_rad);
  const double s2 =
      red.area_px * std::sin(2.0 * red.axis_rad) + green.area_px * std::sin(2.0 * green.axis_rad);
  const double axis_rad = 0.5 * std::atan2(s2, c2);
  double a = -std::sin(axis_rad), b = std::cos(axis_rad);
  if (a * (green.cx - red.cx) + b * (green.cy - red.cy) < 0.0) a = -a, b = -b;
  m.west_image_rad = std::atan2(b, a);
  const double px_per_m = 0.5 * (red.long_px + green.long_px) / layout.rect_height_m;
  m.east_u = -a * px_per_m;
  m.east_v = -b * px_per_m;
  m.north_u = b * px_per_m;
  m.north_v = -a * px_per_m;
  return m;
}

float dot_threshold_ratio(const DetectorParams& params, double blur_px, double red_dot_px) {
  if (blur_px < 0.0 || red_dot_px <= 0.0) return params.dot_threshold_ratio;
  const double span = params.blur_shift_full - params.blur_shift_start;
  const double x =
      length_2d(blur_px, params.sampling_blur_px) / red_dot_px - params.blur_shift_start;
  const double f = span > 0.0 ? std::clamp(x / span, 0.0, 1.0) : (x >= 0.0 ? 1.0 : 0.0);
  return params.dot_threshold_ratio + static_cast<float>(f) * params.dot_threshold_blur_shift;
}

CodeReading read_code(const ImageView& frame, const MarkerFrame& marker, bool red,
                      const CeilingLayout& layout, const DetectorParams& params,
                      float threshold_ratio, DotSearch search) {
  const bool from_edges = search == DotSearch::kFromEdges;
  CodeReading out;
  const double e_m = red ? layout.red_centre_e_m() : layout.green_centre_e_m();
  const double dot_e_m = red ? layout.red_dot_e_m : layout.green_dot_e_m;
  const double dot_n_m = red ? layout.red_dot_n_m : layout.green_dot_n_m;
  const double limit_n_m = reference_limit_n_m(layout);
  Brightness ref_sum{0.0, 0.0};
  int ref_count = 0;
  for (int k = 0; k <= layout.bits; ++k) {
    const double n_m = layout.slot_n_m(0) + 0.5 * layout.slot_pitch_m - k * layout.slot_pitch_m;
    if (std::abs(n_m) > limit_n_m) continue;
    const Brightness b =
        from_edges ? line_brightness(frame, marker, e_m, n_m, reference_spread_e_m(layout))
                   : patch_brightness(frame, marker, e_m, n_m, reference_spread_e_m(layout),
                                      kReferenceSpreadN * dot_n_m);
    if (b[0] < 0.0) return out;
    ref_sum[0] += b[0];
    ref_sum[1] += b[1];
    ++ref_count;
  }
  if (ref_count == 0) return out;
  const Brightness reference{ref_sum[0] / ref_count, ref_sum[1] / ref_count};
  if (reference[0] < 1.0 || reference[1] < 1.0) return out;
  const double search_m =
      from_edges ? std::min(params.dot_search_m, kEdgePlacedDotSearch_m) : params.dot_search_m;
  const double px_per_m = length_2d(marker.north_u, marker.north_v);
  // One pixel, or a sixth of the dot's height in large images.
  const double step_m = std::max(px_per_m > 0.0 ? 1.0 / px_per_m : search_m,
                                 (red ? layout.red_dot_n_m : layout.green_dot_n_m) / 6.0);
  const int search_steps = std::clamp(static_cast<int>(search_m / step_m), 0, 32);
  int code = 0;
  double margin = 1.0;
  for (int k = 0; k < layout.bits; ++k) {
    // The dot's darkest line: lines across the slot (three points, a
    // quarter of the dot's width apart) a pixel apart over ±search_m
    // along North; the darkest is the dot's core wherever blur, a rectangle
    // eaten by glare or a slightly wrong scale put it. The search stays
    // clear of the neighbouring slots' dots (pitch 4 in).
    // The slot's ratio is the lower of the two measures' ratios: each is
    // ≈ 1 on an empty slot, and a dot darkens both.
    double ratio = -1.0;
    for (int step = -search_steps; step <= search_steps; ++step) {
      const Brightness line =
          line_brightness(frame, marker, e_m, layout.slot_n_m(k) + step * step_m, 0.25 * dot_e_m);
      if (line[0] < 0.0) return out;
      const double r = std::min(line[0] / reference[0], line[1] / reference[1]);
      ratio = ratio < 0.0 ? r : std::min(ratio, r);
    }
    out.ratio[k] = static_cast<float>(ratio);
    if (ratio < threshold_ratio) code |= 1 << (layout.bits - 1 - k);
    margin = std::min(margin, std::abs(ratio - threshold_ratio));
  }
  out.ok = true;
  out.code = code;
  out.margin = static_cast<float>(margin);
  return out;
}

bool dark_area_consistent(const RectangleCandidate& rect, int code, bool red,
                          const CeilingLayout& layout, double px_per_m) {
  const double dot_area_px =
      0.25 * std::numbers::pi * px_per_m * px_per_m *
      (red ? layout.red_dot_e_m * layout.red_dot_n_m : layout.green_dot_e_m * layout.green_dot_n_m);
  const int dots = std::popcount(static_cast<unsigned>(code));
  // Blur and the dark threshold shrink dots, never grow them much: allow the
  // code's dots, most of one more, and 2 % of the rectangle for noise.
  return rect.dark_px <= (dots + 0.75) * dot_area_px + 0.02 * rect.area_px;
}

}  // namespace ceilpose
