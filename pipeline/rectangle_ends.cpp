#include "pipeline/rectangle_ends.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "core/int_rounding.h"
#include "core/length_2d.h"
#include "core/pixel_read.h"

namespace ceilpose {
namespace {

constexpr int kMaxSamples = 64;
// Parallel profiles across one edge, averaged into one edge point, at these
// fractions of the offset either side of it. Darkest levels: two (a third
// in the middle cost 30 µs a frame and bought nothing measurable: the
// levels' phase errors, below, outweighed the noise). Linear light: four,
// which halve the noise of an edge-tracked frame, whose edges alone position
// it (unseen drive, 25 ms readout: tracked frames' sd 0.034 → 0.024 mm).
constexpr std::array<double, 2> kTwoProfiles{-1.0, 1.0};
constexpr std::array<double, 4> kFourProfiles{-1.0, -1.0 / 3.0, 1.0 / 3.0, 1.0};
// Their distance from the point along an end (1 in inside the long edges;
// the rail along the shared edge is 0.5 in wide) and along a long side
// (clear of the dots of the slots either side: a green dot reaches 1 in from
// its slot).
constexpr double kEndProfileOffset_m = 1.5 * kInch_m;
constexpr double kSideProfileOffset_m = 0.6 * kInch_m;
// Below this rise from rectangle to tile (the profile's levels, 0–255) an edge is
// not measured: the tile is not what lies beyond it.
constexpr double kMinContrast = 30.0;
// A tile at or above this level is clipped.
constexpr double kClipLevel = 250.0;

// Linear light (0–1) of an sRGB-encoded level, as cameras encode it.
const std::array<float, 256>& linear_of_level() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (size_t i = 0; i < t.size(); ++i) {
      const double c = static_cast<double>(i) / 255.0;
      t[i] = static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
    }
    return t;
  }();
  return table;
}

// The darkest channel's level (0–255) at (u, v), bilinear: red and green
// print far below the tile in it. False outside the frame.
bool darkest_at(const ImageView& frame, double u, double v, double* level) {
  const int x0 = floor_int(u), y0 = floor_int(v);
  if (x0 < 0 || y0 < 0 || x0 + 1 >= frame.width || y0 + 1 >= frame.height) return false;
  const double fu = u - x0, fv = v - y0;
  std::array<uint8_t, 4> c;
  read_darkest_2x2(frame, x0, y0, &c);
  *level = (1 - fv) * ((1 - fu) * c[0] + fu * c[1]) + fv * ((1 - fu) * c[2] + fu * c[3]);
  return true;
}

// Where the level crosses 25 % and 75 % of the way from rectangle to tile,
// and where the edge is, in metres from the nominal edge along the profile
// (outwards); NaN: not crossed, or no edge to measure.
struct Crossings {
  double at25 = NAN, at75 = NAN, at_edge = NAN;
};

// How a profile samples: `samples` steps of `step_m` centred on the edge,
// half_m from it to either end.
struct ProfileSteps {
  double step_m = 0.0;
  int samples = 0;
  double half_m = 0.0;
};

// Darkest levels: `samples` spread over exactly ±kEdgeProfileHalf_m.
ProfileSteps fitted_steps(int samples) {
  return {2.0 * kEdgeProfileHalf_m / (samples - 1), samples, kEdgeProfileHalf_m};
}

// Linear light: a step that moves exactly one pixel along the image axis the
// profile (marker direction (de, dn)) runs closest to, as many as fit in
// ±kEdgeProfileHalf_m. The edge is the integral of the bilinear
// interpolant, which bends at every pixel line; whole-pixel steps meet the
// bends at one phase, so the sum is exact for an axis-aligned edge and
// within ~0.008 px at any angle (steps fitted to the profile's length,
// ~1.08 px, erred up to 0.03 px with the edge's phase). Zero samples: the
// marker frame has no scale.
ProfileSteps axis_steps(const MarkerFrame& marker, double de, double dn) {
  const double du_per_m = de * marker.east_u + dn * marker.north_u;
  const double dv_per_m = de * marker.east_v + dn * marker.north_v;
  const double axis_px_per_m = std::max(std::abs(du_per_m), std::abs(dv_per_m));
  ProfileSteps out;
  if (!(axis_px_per_m > 0.0)) return out;
  out.step_m = 1.0 / axis_px_per_m;
  out.samples =
      std::clamp(static_cast<int>(2.0 * kEdgeProfileHalf_m / out.step_m) + 1, 5, kMaxSamples);
  out.half_m = 0.5 * (out.samples - 1) * out.step_m;
  return out;
}

// The levels of a kDarkestLevel profile, which its edge is measured in
// too: bilinear samples over ±steps.half_m. False when one leaves the frame.
bool read_fitted_profile(const ImageView& frame, const MarkerFrame& marker, double e_m, double n_m,
                         double de, double dn, const ProfileSteps& steps, double* level) {
  for (int k = 0; k < steps.samples; ++k) {
    const double s_m = -steps.half_m + k * steps.step_m;
    double u = 0.0, v = 0.0;
    marker.project(e_m + s_m * de, n_m + s_m * dn, &u, &v);
    if (!darkest_at(frame, u, v, &level[k])) return false;
  }
  return true;
}

// A byte's level (0–255) and its linear light, side by side: a bilinear
// sample interpolates both with two-lane arithmetic, each lane the same
// operations as alone (GCC vector extension: SSE2 on x86-64, NEON on
// arm64). The linear light is the float table's value, exactly.
typedef double LevelLight __attribute__((vector_size(16)));
using LevelLightTable = std::array<LevelLight, 256>;

// A frame whose edge level is one byte of each pixel: a channel of RGB or
// BGR, a YUV frame's luma, grey. Its level (YUV luma to full range) and
// linear light come from a table of that byte.
struct BytePlane {
  const uint8_t* first = nullptr;  // pixel (0, 0)'s byte
  ptrdiff_t pixel_bytes = 0, row_bytes = 0;
  const LevelLightTable* table = nullptr;
};

template <bool kYuvLuma>
const BytePlane& byte_tables() {
  static const BytePlane tables = [] {
    static LevelLightTable table{};
    for (int i = 0; i < 256; ++i) {
      const uint8_t l = kYuvLuma ? yuv_channel(yuv_luma_part(i), 0) : static_cast<uint8_t>(i);
      table[static_cast<size_t>(i)] = LevelLight{static_cast<double>(l), linear_of_level()[l]};
    }
    BytePlane t;
    t.table = &table;
    return t;
  }();
  return tables;
}

// False where the level is not one byte (RGB whose chroma was halved gives
// its luma, computed from three; MJPEG has no pixels).
bool byte_plane(const ImageView& frame, EdgeChannel channel, BytePlane* out) {
  const int rgb_offset = channel == EdgeChannel::kRed ? 0 : 1;
  int offset = 0;
  switch (frame.format) {
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24:
      if (channel == EdgeChannel::kLuma) return false;
      *out = byte_tables<false>();
      out->pixel_bytes = 3;
      offset = frame.format == PixelFormat::kRgb24 ? rgb_offset : 2 - rgb_offset;
      break;
    case PixelFormat::kYuyv:
    case PixelFormat::kNv12:
    case PixelFormat::kYuv420:
      *out = byte_tables<true>();
      out->pixel_bytes = frame.format == PixelFormat::kYuyv ? 2 : 1;
      break;
    case PixelFormat::kGray8:
      *out = byte_tables<false>();
      out->pixel_bytes = 1;
      break;
    case PixelFormat::kMjpeg:
      return false;
  }
  out->first = frame.data + offset;
  out->row_bytes = frame.stride_bytes;
  return true;
}

// What every profile of one rectangle reads: the frame, the marker frame
// placing it, what its edges are measured in, and the byte plane of its
// edge level where there is one (found once a rectangle, not once a
// profile: ~50 instructions a profile).
struct EdgeReading {
  const ImageView& frame;
  const MarkerFrame& marker;
  EdgeLevels levels;
  EdgeChannel channel;
  BytePlane plane;
  bool has_plane = false;

  EdgeReading(const ImageView& f, const MarkerFrame& m, EdgeLevels l, EdgeChannel c)
      : frame(f), marker(m), levels(l), channel(c) {
    has_plane = byte_plane(f, c, &plane);
  }
};

// The same for a kLinearLight profile over axis_steps, and its linear
// light. Each step moves one whole pixel along the dominant axis, so the
// bilinear weights along it are the same for every sample: the profile is
// stepped rather than projected (a tracked 640×480 drive frame's
// measuring, warm: RGB 87 → 58 µs, YUYV 99 → 82 µs). `quad(u_major, a, b)`
// gives the edge levels' bytes at (major, minor) (a, b), (a + 1, b),
// (a, b + 1), (a + 1, b + 1); `table` their level and linear light. False
// when a sample leaves the frame.
template <typename Quad>
bool read_axis_profile(const ImageView& frame, const MarkerFrame& marker, double e_m, double n_m,
                       double de, double dn, const ProfileSteps& steps,
                       const LevelLightTable& table, Quad quad, double* level, double* edge) {
  const double du_per_m = de * marker.east_u + dn * marker.north_u;
  const double dv_per_m = de * marker.east_v + dn * marker.north_v;
  const bool u_major = std::abs(du_per_m) >= std::abs(dv_per_m);
  double u = 0.0, v = 0.0;
  marker.project(e_m - steps.half_m * de, n_m - steps.half_m * dn, &u, &v);
  const double major = u_major ? u : v;
  double minor = u_major ? v : u;
  const double minor_step = (u_major ? dv_per_m : du_per_m) * steps.step_m;
  const int major_step = (u_major ? du_per_m : dv_per_m) > 0.0 ? 1 : -1;
  const int major_limit = u_major ? frame.width : frame.height;
  const int minor_limit = u_major ? frame.height : frame.width;
  const int a0 = floor_int(major);
  const double fa = major - a0;
  // Checked per sample only near the frame's border: inside by a pixel
  // more than the profile's extent, no sample's rounding can leave it: the
  // check was 14 of a sample's ~60 instructions, 1207 → 1135 a profile of
  // 12 samples (640×480 YUYV drive).
  const int a_last = a0 + (steps.samples - 1) * major_step;
  const double minor_last = minor + (steps.samples - 1) * minor_step;
  const bool inside = std::min(a0, a_last) >= 0 && std::max(a0, a_last) + 1 < major_limit &&
                      std::min(minor, minor_last) >= 1.0 &&
                      std::max(minor, minor_last) + 2.0 < minor_limit;
  // The minor coordinate's floor is moved on with it rather than taken
  // afresh: a step moves it by at most a pixel (the major axis is the
  // longer), so one comparison a sample, in the step's direction, replaces
  // a floor_int and a conversion (~4 instructions a sample; the same b).
  auto read = [&](auto checked, auto rising) {
    int a = a0;
    int b = floor_int(minor);
    double b_floor = b;
    for (int k = 0; k < steps.samples; ++k, a += major_step, minor += minor_step) {
      if constexpr (rising) {
        while (minor >= b_floor + 1.0) b_floor += 1.0, ++b;
      } else {
        while (minor < b_floor) b_floor -= 1.0, --b;
      }
      if (checked && (a < 0 || a + 1 >= major_limit || b < 0 || b + 1 >= minor_limit)) return false;
      const double fb = minor - b_floor;
      const auto [c00, c10, c01, c11] = quad(u_major, a, b);
      const LevelLight s = (1 - fb) * ((1 - fa) * table[c00] + fa * table[c10]) +
                           fb * ((1 - fa) * table[c01] + fa * table[c11]);
      level[k] = s[0];
      edge[k] = s[1];
    }
    return true;
  };
  const bool rising = minor_step >= 0.0;
  if (inside)
    return rising ? read(std::false_type{}, std::true_type{})
                  : read(std::false_type{}, std::false_type{});
  return rising ? read(std::true_type{}, std::true_type{})
                : read(std::true_type{}, std::false_type{});
}

// A kLinearLight profile's levels: from a byte plane, four bytes at fixed
// offsets per sample; else (RGB whose chroma was halved: its luma) each
// pixel's level computed.
bool read_linear_profile(const EdgeReading& r, double e_m, double n_m, double de, double dn,
                         const ProfileSteps& steps, double* level, double* edge) {
  const ImageView& frame = r.frame;
  if (r.has_plane) {
    const BytePlane& plane = r.plane;
    return read_axis_profile(
        frame, r.marker, e_m, n_m, de, dn, steps, *plane.table,
        [&](bool u_major, int a, int b) {
          const ptrdiff_t major_bytes = u_major ? plane.pixel_bytes : plane.row_bytes;
          const ptrdiff_t minor_bytes = u_major ? plane.row_bytes : plane.pixel_bytes;
          const uint8_t* p = plane.first + a * major_bytes + b * minor_bytes;
          return std::array<uint8_t, 4>{p[0], p[major_bytes], p[minor_bytes],
                                        p[major_bytes + minor_bytes]};
        },
        level, edge);
  }
  const BytePlane& identity = byte_tables<false>();
  bool inside = false;
  with_pixel_format(frame.format, [&](auto tag) {
    constexpr PixelFormat F = decltype(tag)::value;
    inside = read_axis_profile(
        frame, r.marker, e_m, n_m, de, dn, steps, *identity.table,
        [&](bool u_major, int a, int b) {
          auto read = [&](int major_px, int minor_px) {
            return u_major ? pixel_edge_level<F>(frame, major_px, minor_px, r.channel)
                           : pixel_edge_level<F>(frame, minor_px, major_px, r.channel);
          };
          return std::array<uint8_t, 4>{read(a, b), read(a + 1, b), read(a, b + 1),
                                        read(a + 1, b + 1)};
        },
        level, edge);
  });
  return inside;
}

// One profile through marker point (e_m, n_m) on the edge along the unit
// marker-frame direction (de, dn), pointing out of the rectangle. False when
// it leaves the frame or the contrast is too low.
bool profile(const EdgeReading& r, double e_m, double n_m, double de, double dn,
             const ProfileSteps& steps, bool with_spread, Crossings* out) {
  const int samples = steps.samples;
  const double step_m = steps.step_m;
  // Levels (contrast, blur) and what the edge is measured in (the darkest
  // level itself, or the channel's linear light).
  std::array<double, kMaxSamples> level, edge;
  bool inside = false;
  if (r.levels == EdgeLevels::kDarkestLevel) {
    inside = read_fitted_profile(r.frame, r.marker, e_m, n_m, de, dn, steps, level.data());
    edge = level;
  } else {
    inside = read_linear_profile(r, e_m, n_m, de, dn, steps, level.data(), edge.data());
  }
  if (!inside) return false;
  const double low = 0.5 * (level[0] + level[1]);
  const double high = 0.5 * (level[samples - 1] + level[samples - 2]);
  if (high - low < kMinContrast) return false;
  // The first upward crossing of a share of the rise: of 25 and 75 % for
  // the spread (only the ends': a long side's is not the marker's blur).
  // Each share scans only up to its own crossing. Every share between 0 and
  // 1 is crossed: low and high are means of two end samples, so one of
  // level[0..1] lies at or below low and one of the last two at or above
  // high, after it.
  auto first_crossing = [&](double share) {
    const double target = low + share * (high - low);
    for (int k = 1; k < samples; ++k) {
      if (level[k] >= target && level[k - 1] < target)
        return -steps.half_m +
               ((k - 1) + (target - level[k - 1]) / (level[k] - level[k - 1])) * step_m;
    }
    return static_cast<double>(NAN);
  };
  if (with_spread) {
    out->at25 = first_crossing(0.25);
    out->at75 = first_crossing(0.75);
  }
  // The edge: where a sharp step with the profile's area would be (the
  // rise's shortfall summed from the inner end), so every sample counts
  // rather than the two around the half-way level: on tilted independent
  // renders p99 1.3-1.8 mm against 1.3-2.4 mm by the half-way crossing.
  // Not a rise into the sensor's ceiling: a clipped rise is no longer
  // symmetric about the edge, and its shift varies with the edge's angle (a
  // level frame of a +1.9 EV render chose a tilt and was 2.8 mm off). (It
  // rises through half-way, as through every share: above.)
  if (high >= kClipLevel) return true;
  // Under kLinearLight the area is summed in linear light: a pixel
  // straddling the edge holds the area-weighted mean of the two sides'
  // light, which its sRGB level does not (half covered, it reads ~70 % of
  // the way up), so on levels the edge moves with its phase against the
  // pixel grid: ±0.07–0.15 px on the simulator's axis-aligned edges, which
  // no common edge offset absorbs. Nor in the darkest channel: across the
  // edge it switches channel (the tile's darkest is blue, the red
  // rectangle's green), which bends the rise. Whole sweeps keep the darkest
  // levels (docs/decisions.md "Edges in linear light").
  const double edge_low = 0.5 * (edge[0] + edge[1]);
  const double edge_high = 0.5 * (edge[samples - 1] + edge[samples - 2]);
  const double per_rise = 1.0 / (edge_high - edge_low);
  double shortfall = 0.0;  // in steps
  for (int k = 0; k < samples; ++k)
    shortfall += 1.0 - std::clamp((edge[k] - edge_low) * per_rise, 0.0, 1.0);
  // The trapezoid's end samples count half.
  shortfall -= 0.5 * (2.0 - std::clamp((edge[0] - edge_low) * per_rise, 0.0, 1.0) -
                      std::clamp((edge[samples - 1] - edge_low) * per_rise, 0.0, 1.0));
  out->at_edge = -steps.half_m + shortfall * step_m;
  return true;
}

// The edge point of the edge through (e_m, n_m) with outward direction
// (de, dn), from parallel profiles at `fractions` of `offset_m` along it;
// *spread_m, unless null: their mean 25–75 % distance (NaN: not measured).
template <size_t N>
EdgeCrossing cross_edge(const EdgeReading& r, double e_m, double n_m, double de, double dn,
                        double offset_m, const std::array<double, N>& fractions,
                        const ProfileSteps& steps, double* spread_m) {
  const MarkerFrame& marker = r.marker;
  EdgeCrossing out;
  double spread_sum_m = 0.0;
  int spreads = 0;
  double e_sum = 0.0, n_sum = 0.0, u_sum = 0.0, v_sum = 0.0;
  int found = 0;
  for (double fraction : fractions) {
    // Along the edge is (−dn, de).
    const double along_m = fraction * offset_m;
    const double pe = e_m - along_m * dn, pn = n_m + along_m * de;
    Crossings c;
    if (!profile(r, pe, pn, de, dn, steps, spread_m != nullptr, &c)) continue;
    if (!std::isnan(c.at25) && !std::isnan(c.at75)) {
      spread_sum_m += c.at75 - c.at25;
      ++spreads;
    }
    if (std::isnan(c.at_edge)) continue;
    double u = 0.0, v = 0.0;
    marker.project(pe + c.at_edge * de, pn + c.at_edge * dn, &u, &v);
    e_sum += pe;
    n_sum += pn;
    u_sum += u;
    v_sum += v;
    ++found;
  }
  if (spread_m != nullptr) *spread_m = spreads > 0 ? spread_sum_m / spreads : NAN;
  // An edge crossed by fewer than all profiles is partly hidden, dirty or
  // out of the frame: its mean would lean towards the part that was seen.
  if (found < static_cast<int>(N)) return out;
  out.found = true;
  out.e_m = e_sum / found;
  out.n_m = n_sum / found;
  out.u_px = u_sum / found;
  out.v_px = v_sum / found;
  const double nu = de * marker.east_u + dn * marker.north_u;
  const double nv = de * marker.east_v + dn * marker.north_v;
  const double len = length_2d(nu, nv);
  out.normal_u = nu / len;
  out.normal_v = nv / len;
  return out;
}

// One edge under `levels`: two profiles over fitted steps, or four over
// axis steps.
EdgeCrossing measure_edge(const EdgeReading& r, double e_m, double n_m, double de, double dn,
                          double offset_m, int fitted_samples, double* spread_m) {
  if (r.levels == EdgeLevels::kDarkestLevel)
    return cross_edge(r, e_m, n_m, de, dn, offset_m, kTwoProfiles, fitted_steps(fitted_samples),
                      spread_m);
  const ProfileSteps steps = axis_steps(r.marker, de, dn);
  if (steps.samples == 0) {
    if (spread_m != nullptr) *spread_m = NAN;
    return {};
  }
  return cross_edge(r, e_m, n_m, de, dn, offset_m, kFourProfiles, steps, spread_m);
}

}  // namespace

RectangleEdges measure_edges(const ImageView& frame, const MarkerFrame& marker, bool red,
                             const CeilingLayout& layout, EdgeLevels levels) {
  RectangleEdges out;
  const double centre_e_m = red ? layout.red_centre_e_m() : layout.green_centre_e_m();
  const EdgeChannel channel = frame.chroma_halved ? EdgeChannel::kLuma
                              : red               ? EdgeChannel::kGreen
                                                  : EdgeChannel::kRed;
  const double px_per_m = length_2d(marker.north_u, marker.north_v);
  if (!(px_per_m > 0.0)) return out;
  const EdgeReading reading(frame, marker, levels, channel);
  const int samples =
      std::clamp(static_cast<int>(2.0 * kEdgeProfileHalf_m * px_per_m) + 1, 5, kMaxSamples);
  double spread_sum_m = 0.0;
  int spreads = 0;
  for (int s = 0; s < 2; ++s) {
    const double dn = s == 0 ? 1.0 : -1.0;
    double spread_m = NAN;
    out.end[static_cast<size_t>(s)] =
        measure_edge(reading, centre_e_m, dn * 0.5 * layout.rect_height_m, 0.0, dn,
                     kEndProfileOffset_m, samples, &spread_m);
    if (std::isnan(spread_m)) continue;
    spread_sum_m += spread_m;
    ++spreads;
  }
  if (spreads > 0) out.spread_px = spread_sum_m / spreads * px_per_m;
  // The outer long side: e = ±5 in, between each pair of neighbouring slots.
  const double de = red ? 1.0 : -1.0;
  for (int k = 0; k + 1 < layout.bits && out.side_count < kMaxSideCrossings; ++k) {
    const double n_m = 0.5 * (layout.slot_n_m(k) + layout.slot_n_m(k + 1));
    const EdgeCrossing c = measure_edge(reading, de * layout.rect_width_m, n_m, de, 0.0,
                                        kSideProfileOffset_m, samples, nullptr);
    if (c.found) out.side[static_cast<size_t>(out.side_count++)] = c;
  }
  return out;
}

double edge_spread_px(const ImageView& frame, const MarkerFrame& marker, bool red,
                      const CeilingLayout& layout) {
  return measure_edges(frame, marker, red, layout).spread_px;
}

}  // namespace ceilpose
