#include "sim/ceiling_scene.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace ceilpose::sim {
namespace {

// Light panels are brighter than anything the sensor records unsaturated at
// unit gain, as real fixtures are; slightly cool white.
constexpr LinearRgb kFixtureRadiance{2.9f, 3.0f, 3.2f};
// One tile in this many holds a panel (in expectation).
constexpr uint64_t kFixtureOneIn = 5;
// Clearance kept between fixtures/clutter and markers or rails.
constexpr double kClearance_m = 0.0127;

double unit_double(uint64_t h) { return static_cast<double>(h >> 11) * 0x1.0p-53; }

// The marker-free part of a tile interior, relative to the tile centre:
// objects whose E–W extent stays inside ±limit_e may use the tile's whole
// N–S span, and vice versa (markers occupy the four corners only).
struct TileRoom {
  double limit_e_m;     // E–W half span between the markers of a tile edge
  double limit_n_m;     // N–S half span between the markers of a tile edge
  double limit_free_m;  // half span between the rails
};

TileRoom tile_room(const CeilingLayout& l) {
  const double half_tile = 0.5 * l.grid_m;
  return {half_tile - l.rect_width_m - kClearance_m,
          half_tile - 0.5 * l.rect_height_m - kClearance_m,
          half_tile - 0.5 * l.rail_width_m - kClearance_m};
}

}  // namespace

uint64_t mix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

float srgb_to_linear(uint8_t v) {
  const double c = v / 255.0;
  return static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
}

CeilingScene::CeilingScene(const CeilingLayout& layout, uint64_t seed,
                           std::shared_ptr<const LaidCeiling> laid)
    : layout_(layout),
      laid_(std::move(laid)),
      seed_(seed),
      inv_grid_(1.0 / layout.grid_m),
      half_w_m_(layout.rect_width_m),
      half_h_m_(0.5 * layout.rect_height_m),
      marker_reach_m_(std::hypot(half_w_m_, half_h_m_)) {
  auto lin = [](Rgb c) {
    return LinearRgb{srgb_to_linear(c.r), srgb_to_linear(c.g), srgb_to_linear(c.b)};
  };
  if (laid_ != nullptr) {
    // How far past its node's half grid the farthest-reaching marker goes,
    // in whole grid steps.
    double past_m = 0.0;
    for (int j = 0; j < laid_->side(); ++j)
      for (int i = 0; i < laid_->side(); ++i) {
        const LaidMarker& m = laid_->at(i, j);
        if (!m.present) continue;
        const double off_m =
            std::max(std::abs(m.x_m - i * layout.grid_m), std::abs(m.y_m - j * layout.grid_m));
        past_m = std::max(past_m, off_m + marker_reach_m_ - 0.5 * layout.grid_m);
      }
    laid_reach_nodes_ = static_cast<int>(std::ceil(past_m * inv_grid_));
  }
  colours_[kMaterialNone] = {0.0f, 0.0f, 0.0f};
  colours_[kMaterialTile] = lin(layout.tile);
  colours_[kMaterialRail] = lin(layout.rail);
  colours_[kMaterialRed] = lin(layout.red);
  colours_[kMaterialGreen] = lin(layout.green);
  colours_[kMaterialDot] = lin(layout.dot);
  colours_[kMaterialFixture] = kFixtureRadiance;

  // Clutter: things a real ceiling carries that share the markers' colours —
  // discs (exit signs, stickers), rotated strips, and lone rectangles of a
  // marker rectangle's exact size and colour that have no partner.
  const std::array<Rgb, 6> palette{layout.red,       layout.green,     Rgb{220, 50, 30},
                                   Rgb{30, 140, 90}, Rgb{180, 20, 60}, Rgb{90, 170, 40}};
  const TileRoom room = tile_room(layout);
  const int n_codes = layout.codes();
  for (int k = 0; k < kMaxClutterObjects; ++k) {
    uint64_t h = mix64(seed ^ mix64(0xC1u + static_cast<uint64_t>(k)));
    auto next = [&h] {
      h = mix64(h);
      return unit_double(h);
    };
    ClutterObject& o = clutter_[k];
    const int kind = static_cast<int>(next() * 3.0);
    const double angle = next() * 3.141592653589793;
    if (kind == 0) {
      o.disc = true;
      o.half_a_m = (1.0 + 2.5 * next()) * kInch_m;
      o.half_b_m = o.half_a_m * (0.6 + 0.4 * next());
    } else if (kind == 1) {
      o.half_a_m = (1.0 + 2.0 * next()) * kInch_m;
      o.half_b_m = (2.0 + 4.0 * next()) * kInch_m;
    } else {
      o.half_a_m = 0.5 * layout.rect_width_m;
      o.half_b_m = 0.5 * layout.rect_height_m;
    }
    const double a = kind == 2 ? 0.0 : angle;
    o.cos_rad = std::cos(a);
    o.sin_rad = std::sin(a);
    const double ca = std::abs(o.cos_rad), sa = std::abs(o.sin_rad);
    if (o.disc) {
      o.bound_x_m =
          std::sqrt(o.half_a_m * o.half_a_m * ca * ca + o.half_b_m * o.half_b_m * sa * sa);
      o.bound_y_m =
          std::sqrt(o.half_a_m * o.half_a_m * sa * sa + o.half_b_m * o.half_b_m * ca * ca);
    } else {
      o.bound_x_m = o.half_a_m * ca + o.half_b_m * sa;
      o.bound_y_m = o.half_a_m * sa + o.half_b_m * ca;
    }
    o.colour = kind == 2 ? (next() < 0.5 ? layout.red : layout.green)
                         : palette[static_cast<size_t>(next() * palette.size()) % palette.size()];
    // Tiles from one beyond the first marker line to the last one.
    const int ti = -1 + static_cast<int>(next() * (n_codes + 1));
    const int tj = -1 + static_cast<int>(next() * (n_codes + 1));
    const bool restrict_e =
        o.bound_x_m <= room.limit_e_m && (next() < 0.5 || o.bound_y_m > room.limit_n_m);
    double span_x = 0.0, span_y = 0.0;
    if (restrict_e) {
      span_x = room.limit_e_m - o.bound_x_m;
      span_y = room.limit_free_m - o.bound_y_m;
    } else {
      span_x = room.limit_free_m - o.bound_x_m;
      span_y = std::max(0.0, room.limit_n_m - o.bound_y_m);
    }
    o.x_m = (ti + 0.5) * layout.grid_m + (2.0 * next() - 1.0) * std::max(0.0, span_x);
    o.y_m = (tj + 0.5) * layout.grid_m + (2.0 * next() - 1.0) * std::max(0.0, span_y);
    colours_[kMaterialClutterBase + k] = lin(o.colour);
  }
  // Fixtures of the tiles near the grid, looked up per sample instead of hashed.
  fixture_half_ns_ = {room.limit_e_m, room.limit_free_m};
  fixture_half_ew_ = {room.limit_free_m, room.limit_n_m};
  fixture_tiles_side_ = n_codes + 2 * kFixtureTableMargin;
  fixture_tiles_.assign(static_cast<size_t>(fixture_tiles_side_) * fixture_tiles_side_, 0);
  for (int tj = 0; tj < fixture_tiles_side_; ++tj)
    for (int ti = 0; ti < fixture_tiles_side_; ++ti) {
      double half_e_m = 0.0, half_n_m = 0.0;
      if (fixture_on_tile(ti - kFixtureTableMargin, tj - kFixtureTableMargin, &half_e_m, &half_n_m))
        fixture_tiles_[static_cast<size_t>(tj) * fixture_tiles_side_ + ti] =
            half_e_m < half_n_m ? kFixtureNorthSouth : kFixtureEastWest;
    }
}

bool CeilingScene::fixture_on_tile(int64_t ti, int64_t tj, double* half_e_m,
                                   double* half_n_m) const {
  const uint64_t h = mix64(seed_ ^ mix64(static_cast<uint64_t>(ti) * 0x9E3779B1ull ^
                                         mix64(static_cast<uint64_t>(tj) + 0xF1u)));
  if (h % kFixtureOneIn != 0) return false;
  // Panels run N–S or E–W between the markers of the tile's corners.
  const TileRoom room = tile_room(layout_);
  const bool north_south = ((h >> 20) & 1u) != 0;
  *half_e_m = north_south ? room.limit_e_m : room.limit_free_m;
  *half_n_m = north_south ? room.limit_free_m : room.limit_n_m;
  return true;
}

}  // namespace ceilpose::sim
