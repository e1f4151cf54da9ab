#pragma once
// The ceiling of SPEC §1–2 as a function of the ceiling-plane point: which
// material (marker red, green, dot, tile, rail, light fixture, clutter) covers
// (x, y). Fixtures and clutter are placed deterministically from the seed,
// always on tile interiors clear of every marker, so they never overlap one.
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/ceiling_layout.h"
#include "sim/laid_ceiling.h"

namespace ceilpose::sim {

// Material ids. Clutter objects get one id each from kClutterBase on, so that
// each can carry its own colour.
enum Material : uint8_t {
  kMaterialNone = 0,  // the ray misses the ceiling plane
  kMaterialTile,
  kMaterialRail,
  kMaterialRed,
  kMaterialGreen,
  kMaterialDot,
  kMaterialFixture,
  kMaterialClutterBase,
};

inline constexpr int kMaxClutterObjects = 32;
inline constexpr int kMaterialCount = kMaterialClutterBase + kMaxClutterObjects;

// A flat object on the ceiling that is red or green but not a marker.
struct ClutterObject {
  bool disc = false;  // disc (ellipse) or rectangle
  double x_m = 0.0;   // centre in the world
  double y_m = 0.0;
  double half_a_m = 0.0;  // half extent along the object's own first axis
  double half_b_m = 0.0;
  double cos_rad = 1.0;  // orientation of the first axis from +x
  double sin_rad = 0.0;
  double bound_x_m = 0.0;  // half extents of the axis-aligned bounding box
  double bound_y_m = 0.0;
  Rgb colour{};
};

// Linear-light RGB radiance; 1.0 is the brightest level the sensor records
// unsaturated at unit gain.
using LinearRgb = std::array<float, 3>;

// sRGB (8-bit, as printed) to linear light.
float srgb_to_linear(uint8_t v);

class CeilingScene {
 public:
  // `laid`: where the markers really are (null: the nominal grid).
  CeilingScene(const CeilingLayout& layout, uint64_t seed,
               std::shared_ptr<const LaidCeiling> laid = nullptr);

  // Material at ceiling point (x, y). `fixtures` switches light panels on,
  // `clutter_count` selects how many of the scene's clutter objects exist.
  // Hot path: called several hundred thousand times per frame.
  uint8_t material_at(double x_m, double y_m, bool fixtures, int clutter_count) const;

  const CeilingLayout& layout() const { return layout_; }
  const std::array<LinearRgb, kMaterialCount>& linear_colours() const { return colours_; }
  const std::array<ClutterObject, kMaxClutterObjects>& clutter() const { return clutter_; }
  // Whether tile (ti, tj) — the tile whose south-west corner is (ti·g, tj·g) —
  // holds a light panel, and the panel's half extents (E–W, N–S) in metres.
  bool fixture_on_tile(int64_t ti, int64_t tj, double* half_e_m, double* half_n_m) const;

 private:
  // Tiles within this many of the marker grid have their fixture looked up
  // in a table; farther ones are hashed per sample (slower, same result).
  static constexpr int kFixtureTableMargin = 24;
  enum : uint8_t { kNoFixture = 0, kFixtureNorthSouth = 1, kFixtureEastWest = 2 };

  uint8_t marker_material(int i, int j, double e_m, double n_m) const;
  // The material of the marker laid at node (i, j) at (x, y); kMaterialNone
  // where it does not cover the point (or none is there).
  uint8_t laid_material(int i, int j, double x_m, double y_m) const;
  uint8_t fixture_kind(int64_t ti, int64_t tj) const;

  CeilingLayout layout_;
  std::shared_ptr<const LaidCeiling> laid_;
  uint64_t seed_;
  double inv_grid_ = 1.0;
  double half_w_m_ = 0.0;  // marker half extents
  double half_h_m_ = 0.0;
  double marker_reach_m_ = 0.0;  // their half diagonal
  // Rings of grid nodes around the nearest one whose laid markers may reach
  // a point: 0 while every marker lies within its own node's half grid.
  int laid_reach_nodes_ = 0;
  std::array<LinearRgb, kMaterialCount> colours_{};
  std::array<ClutterObject, kMaxClutterObjects> clutter_{};
  std::array<double, 2> fixture_half_ns_{};  // half extents (E–W, N–S) of a N–S panel
  std::array<double, 2> fixture_half_ew_{};
  int fixture_tiles_side_ = 0;
  std::vector<uint8_t> fixture_tiles_;
};

// splitmix64: the one hash every deterministic choice of the simulator uses.
uint64_t mix64(uint64_t x);

// Hot path, inline: the renderer calls these for every pixel corner and
// every sub-sample.

inline uint8_t CeilingScene::fixture_kind(int64_t ti, int64_t tj) const {
  const int64_t a = ti + kFixtureTableMargin, b = tj + kFixtureTableMargin;
  if (a >= 0 && b >= 0 && a < fixture_tiles_side_ && b < fixture_tiles_side_)
    return fixture_tiles_[static_cast<size_t>(b) * fixture_tiles_side_ + static_cast<size_t>(a)];
  double half_e_m = 0.0, half_n_m = 0.0;
  if (!fixture_on_tile(ti, tj, &half_e_m, &half_n_m)) return kNoFixture;
  return half_e_m < half_n_m ? kFixtureNorthSouth : kFixtureEastWest;
}

inline uint8_t CeilingScene::marker_material(int i, int j, double e_m, double n_m) const {
  const CeilingLayout& l = layout_;
  const bool red = e_m >= 0.0;
  const int code = red ? i : j;
  const double pitch = l.slot_pitch_m;
  int k = static_cast<int>(std::floor(((l.bits - 1) * 0.5 * pitch - n_m) / pitch + 0.5));
  k = k < 0 ? 0 : (k > l.bits - 1 ? l.bits - 1 : k);
  if (!l.slot_bit(code, k)) return red ? kMaterialRed : kMaterialGreen;
  const double de = (e_m - (red ? l.red_centre_e_m() : l.green_centre_e_m())) /
                    (0.5 * (red ? l.red_dot_e_m : l.green_dot_e_m));
  const double dn = (n_m - l.slot_n_m(k)) / (0.5 * (red ? l.red_dot_n_m : l.green_dot_n_m));
  if (de * de + dn * dn <= 1.0) return kMaterialDot;
  return red ? kMaterialRed : kMaterialGreen;
}

inline uint8_t CeilingScene::laid_material(int i, int j, double x_m, double y_m) const {
  const LaidMarker& m = laid_->at(i, j);
  if (!m.present) return kMaterialNone;
  const double dx = x_m - m.x_m, dy = y_m - m.y_m;
  // Beyond its half diagonal at any turn: no trigonometry.
  if (std::abs(dx) > marker_reach_m_ || std::abs(dy) > marker_reach_m_) return kMaterialNone;
  const double c = std::cos(m.yaw_rad), s = std::sin(m.yaw_rad);
  const double me = c * dx + s * dy, mn = -s * dx + c * dy;
  if (std::abs(me) > half_w_m_ || std::abs(mn) > half_h_m_) return kMaterialNone;
  return marker_material(m.code_i, m.code_j, me, mn);
}

inline uint8_t CeilingScene::material_at(double x_m, double y_m, bool fixtures,
                                         int clutter_count) const {
  const double gx = x_m * inv_grid_, gy = y_m * inv_grid_;
  const double ri = std::floor(gx + 0.5), rj = std::floor(gy + 0.5);
  const double e = x_m - ri * layout_.grid_m, n = y_m - rj * layout_.grid_m;
  // Markers are drawn over everything; nothing else is placed where they are.
  const int n_codes = layout_.codes();
  const bool on_grid = ri >= 0.0 && rj >= 0.0 && ri < n_codes && rj < n_codes;
  if (laid_ == nullptr) {
    if (on_grid && std::abs(e) <= half_w_m_ && std::abs(n) <= half_h_m_)
      return marker_material(static_cast<int>(ri), static_cast<int>(rj), e, n);
  } else {
    // A hand-laid marker is looked up at its own node first, in its own
    // frame; one glued so far off that it reaches past its node's half grid
    // also at the nodes around (laid_reach_nodes_), so it is drawn whole.
    if (on_grid) {
      const uint8_t own = laid_material(static_cast<int>(ri), static_cast<int>(rj), x_m, y_m);
      if (own != kMaterialNone) return own;
    }
    for (int dj = -laid_reach_nodes_; dj <= laid_reach_nodes_; ++dj) {
      for (int di = -laid_reach_nodes_; di <= laid_reach_nodes_; ++di) {
        const double i = ri + di, j = rj + dj;
        if ((di == 0 && dj == 0) || i < 0.0 || j < 0.0 || i >= n_codes || j >= n_codes) continue;
        const uint8_t near = laid_material(static_cast<int>(i), static_cast<int>(j), x_m, y_m);
        if (near != kMaterialNone) return near;
      }
    }
  }
  for (int k = 0; k < clutter_count; ++k) {
    const ClutterObject& o = clutter_[k];
    const double dx = x_m - o.x_m, dy = y_m - o.y_m;
    if (std::abs(dx) > o.bound_x_m || std::abs(dy) > o.bound_y_m) continue;
    const double a = dx * o.cos_rad + dy * o.sin_rad, b = -dx * o.sin_rad + dy * o.cos_rad;
    const bool inside =
        o.disc ? (a * a) / (o.half_a_m * o.half_a_m) + (b * b) / (o.half_b_m * o.half_b_m) <= 1.0
               : std::abs(a) <= o.half_a_m && std::abs(b) <= o.half_b_m;
    if (inside) return static_cast<uint8_t>(kMaterialClutterBase + k);
  }
  if (fixtures) {
    // floor(g) from round(g) = floor(g + 0.5): one of round(g) and
    // round(g) - 1, exactly (the hot path's two floors fewer).
    const double ti = gx < ri ? ri - 1.0 : ri, tj = gy < rj ? rj - 1.0 : rj;
    if (std::abs(ti) < 1e12 && std::abs(tj) < 1e12) {
      const uint8_t kind = fixture_kind(static_cast<int64_t>(ti), static_cast<int64_t>(tj));
      if (kind != kNoFixture) {
        const auto& half = kind == kFixtureNorthSouth ? fixture_half_ns_ : fixture_half_ew_;
        const double de = x_m - (ti + 0.5) * layout_.grid_m;
        const double dn = y_m - (tj + 0.5) * layout_.grid_m;
        if (std::abs(de) <= half[0] && std::abs(dn) <= half[1]) return kMaterialFixture;
      }
    }
  }
  const double rail_half = 0.5 * layout_.rail_width_m;
  if (std::abs(e) <= rail_half || std::abs(n) <= rail_half) return kMaterialRail;
  return kMaterialTile;
}

}  // namespace ceilpose::sim
