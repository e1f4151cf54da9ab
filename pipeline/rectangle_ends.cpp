#include "pipeline/rectangle_ends.h"

#include <algorithm>
#include <cmath>

#include "core/pixel_read.h"

namespace ceilpose {
namespace {

constexpr int kMaxSamples = 64;
// Parallel profiles across one edge, averaged into one edge point: two,
// either side of the point (a third in the middle cost 30 µs a frame and
// bought nothing measurable).
constexpr int kProfiles = 2;
// Their distance from the point along an end (1 in inside the long edges;
// the rail along the shared edge is 0.5 in wide) and along a long side
// (clear of the dots of the slots either side: a green dot reaches 1 in from
// its slot).
constexpr double kEndProfileOffset_m = 1.5 * kInch_m;
constexpr double kSideProfileOffset_m = 0.6 * kInch_m;
// Below this rise from rectangle to tile (darkest channel, 0–255) an edge is
// not measured: the tile is not what lies beyond it.
constexpr double kMinContrast = 30.0;
// A tile at or above this level (darkest channel) is clipped.
constexpr double kClipLevel = 250.0;

// The darkest channel at an image point, bilinear; negative outside the
// frame. Red and green print far below the tile in it.
double darkest_at(const ImageView& frame, double u, double v) {
  const int x0 = static_cast<int>(std::floor(u)), y0 = static_cast<int>(std::floor(v));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= frame.width || y0 + 1 >= frame.height) return -1.0;
  const double fu = u - x0, fv = v - y0;
  std::array<uint8_t, 4> corner;
  read_darkest_2x2(frame, x0, y0, &corner);
  return (1 - fv) * ((1 - fu) * corner[0] + fu * corner[1]) +
         fv * ((1 - fu) * corner[2] + fu * corner[3]);
}

// Where the level crosses 25 % and 75 % of the way from rectangle to tile,
// and where the edge is, in metres from the nominal edge along the profile
// (outwards); NaN: not crossed, or no edge to measure.
struct Crossings {
  double at25 = NAN, at75 = NAN, at_edge = NAN;
};

// One profile through marker point (e_m, n_m) on the edge along the unit
// marker-frame direction (de, dn), pointing out of the rectangle, a sample
// per pixel. False when it leaves the frame or the contrast is too low.
bool profile(const ImageView& frame, const MarkerFrame& marker, double e_m, double n_m, double de,
             double dn, int samples, Crossings* out) {
  const double step_m = 2.0 * kEdgeProfileHalf_m / (samples - 1);
  std::array<double, kMaxSamples> level;  // samples of them written before any is read
  for (int k = 0; k < samples; ++k) {
    const double s_m = -kEdgeProfileHalf_m + k * step_m;
    double u = 0.0, v = 0.0;
    marker.project(e_m + s_m * de, n_m + s_m * dn, &u, &v);
    level[k] = darkest_at(frame, u, v);
    if (level[k] < 0.0) return false;
  }
  const double low = 0.5 * (level[0] + level[1]);
  const double high = 0.5 * (level[samples - 1] + level[samples - 2]);
  if (high - low < kMinContrast) return false;
  auto crossing = [&](double fraction) {
    const double target = low + fraction * (high - low);
    for (int k = 1; k < samples; ++k) {
      if (level[k] >= target && level[k - 1] < target)
        return -kEdgeProfileHalf_m +
               ((k - 1) + (target - level[k - 1]) / (level[k] - level[k - 1])) * step_m;
    }
    return static_cast<double>(NAN);
  };
  out->at25 = crossing(0.25);
  out->at75 = crossing(0.75);
  // The edge: where a sharp step with the profile's area would be (the
  // rise's shortfall summed from the inner end), so every sample counts
  // rather than the two around the half-way level: on tilted independent
  // renders p99 1.3-1.8 mm against 1.3-2.4 mm by the half-way crossing.
  // Only a profile that rises through half-way, and not into the sensor's
  // ceiling: a clipped rise is no longer symmetric about the edge, and its
  // shift varies with the edge's angle (a level frame of a +1.9 EV
  // render chose a tilt and was 2.8 mm off).
  if (std::isnan(crossing(0.5)) || high >= kClipLevel) return true;
  double shortfall_m = 0.0;
  for (int k = 0; k < samples; ++k) {
    const double rise = std::clamp((level[k] - low) / (high - low), 0.0, 1.0);
    shortfall_m += (k == 0 || k == samples - 1 ? 0.5 : 1.0) * (1.0 - rise) * step_m;
  }
  out->at_edge = -kEdgeProfileHalf_m + shortfall_m;
  return true;
}

// The edge point of the edge through (e_m, n_m) with outward direction
// (de, dn), from kProfiles parallel profiles `offset_m` either side of it;
// *spread_m: their mean 25–75 % distance (NaN: not measured).
EdgeCrossing cross_edge(const ImageView& frame, const MarkerFrame& marker, double e_m, double n_m,
                        double de, double dn, double offset_m, int samples, double* spread_m) {
  EdgeCrossing out;
  double spread_sum_m = 0.0;
  int spreads = 0;
  double e_sum = 0.0, n_sum = 0.0, u_sum = 0.0, v_sum = 0.0;
  int found = 0;
  for (int p = 0; p < kProfiles; ++p) {
    // Along the edge is (−dn, de).
    const double along_m = (p == 0 ? -1.0 : 1.0) * offset_m;
    const double pe = e_m - along_m * dn, pn = n_m + along_m * de;
    Crossings c;
    if (!profile(frame, marker, pe, pn, de, dn, samples, &c)) continue;
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
  *spread_m = spreads > 0 ? spread_sum_m / spreads : NAN;
  // An edge crossed by fewer than all profiles is partly hidden, dirty or
  // out of the frame: its mean would lean towards the part that was seen.
  if (found < kProfiles) return out;
  out.found = true;
  out.e_m = e_sum / found;
  out.n_m = n_sum / found;
  out.u_px = u_sum / found;
  out.v_px = v_sum / found;
  const double nu = de * marker.east_u + dn * marker.north_u;
  const double nv = de * marker.east_v + dn * marker.north_v;
  const double len = std::hypot(nu, nv);
  out.normal_u = nu / len;
  out.normal_v = nv / len;
  return out;
}

}  // namespace

RectangleEdges measure_edges(const ImageView& frame, const MarkerFrame& marker, bool red,
                             const CeilingLayout& layout) {
  RectangleEdges out;
  const double centre_e_m = red ? layout.red_centre_e_m() : layout.green_centre_e_m();
  const double px_per_m = std::hypot(marker.north_u, marker.north_v);
  if (!(px_per_m > 0.0)) return out;
  const int samples =
      std::clamp(static_cast<int>(2.0 * kEdgeProfileHalf_m * px_per_m) + 1, 5, kMaxSamples);
  double spread_sum_m = 0.0;
  int spreads = 0;
  for (int s = 0; s < 2; ++s) {
    const double dn = s == 0 ? 1.0 : -1.0;
    double spread_m = NAN;
    out.end[static_cast<size_t>(s)] =
        cross_edge(frame, marker, centre_e_m, dn * 0.5 * layout.rect_height_m, 0.0, dn,
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
    double spread_m = NAN;
    const EdgeCrossing c = cross_edge(frame, marker, de * layout.rect_width_m, n_m, de, 0.0,
                                      kSideProfileOffset_m, samples, &spread_m);
    if (c.found) out.side[static_cast<size_t>(out.side_count++)] = c;
  }
  return out;
}

double edge_spread_px(const ImageView& frame, const MarkerFrame& marker, bool red,
                      const CeilingLayout& layout) {
  return measure_edges(frame, marker, red, layout).spread_px;
}

}  // namespace ceilpose
