// The ceiling scene: markers win over everything, fixtures and clutter keep
// clear of markers, and the layout is a function of the seed.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "sim/ceiling_scene.h"
#include "sim/laid_ceiling.h"
#include "sim/visibility.h"

namespace ceilpose::sim {
namespace {

bool is_marker_material(uint8_t m) {
  return m == kMaterialRed || m == kMaterialGreen || m == kMaterialDot;
}

TEST(CeilingScene, EveryPointOfEveryMarkerIsMarkerMaterialWithFixturesAndAllClutter) {
  for (uint64_t seed : {1u, 2u, 99u}) {
    const CeilingLayout layout;
    const CeilingScene scene(layout, seed);
    for (int i = 0; i < layout.codes(); ++i)
      for (int j = 0; j < layout.codes(); ++j) {
        const Vec3 c = layout.marker_centre_w(i, j);
        constexpr int kSteps = 24;
        // Just inside the outline: exactly on it, rounding decides.
        for (int a = 0; a <= kSteps; ++a)
          for (int b = 0; b <= kSteps; ++b) {
            const double e = (2.0 * a / kSteps - 1.0) * (layout.rect_width_m - 1e-6);
            const double n = (1.0 * b / kSteps - 0.5) * (layout.rect_height_m - 2e-6);
            ASSERT_TRUE(
                is_marker_material(scene.material_at(c[0] + e, c[1] + n, true, kMaxClutterObjects)))
                << "seed " << seed << " marker " << i << "," << j << " e " << e << " n " << n;
          }
      }
  }
}

// A marker glued so far off its spot that it reaches past its node's half
// grid is drawn whole, not clipped where the next node's cell begins (seeds
// 7-14 at 0.25 m: before, the far end of the marker was tile or rail).
TEST(CeilingScene, AHandLaidMarkerFarOffItsSpotIsDrawnWhole) {
  const CeilingLayout layout;
  for (uint64_t seed = 7; seed <= 14; ++seed) {
    HandLaidOptions o;
    o.seed = seed;
    o.outlier_m = 0.25;
    const auto laid = std::make_shared<const LaidCeiling>(LaidCeiling::hand_laid(layout, o));
    const CeilingScene scene(layout, seed, laid);
    for (int i = 0; i < laid->side(); ++i)
      for (int j = 0; j < laid->side(); ++j) {
        const LaidMarker& m = laid->at(i, j);
        if (!m.present) continue;
        const double c = std::cos(m.yaw_rad), s = std::sin(m.yaw_rad);
        constexpr int kSteps = 16;
        for (int a = 0; a <= kSteps; ++a)
          for (int b = 0; b <= kSteps; ++b) {
            const double e = (2.0 * a / kSteps - 1.0) * (layout.rect_width_m - 1e-6);
            const double n = (1.0 * b / kSteps - 0.5) * (layout.rect_height_m - 2e-6);
            ASSERT_TRUE(is_marker_material(scene.material_at(
                m.x_m + c * e - s * n, m.y_m + s * e + c * n, true, kMaxClutterObjects)))
                << "seed " << seed << " node " << i << "," << j << " e " << e << " n " << n;
          }
      }
  }
}

// Whether two axis-aligned boxes (centre, half extents) overlap.
bool boxes_overlap(double ax, double ay, double ahx, double ahy, double bx, double by, double bhx,
                   double bhy) {
  return std::abs(ax - bx) < ahx + bhx && std::abs(ay - by) < ahy + bhy;
}

TEST(CeilingScene, ClutterBoundingBoxesStayClearOfMarkerOutlines) {
  const CeilingLayout layout;
  const CeilingScene scene(layout, 7);
  for (const ClutterObject& o : scene.clutter())
    for (int i = 0; i < layout.codes(); ++i)
      for (int j = 0; j < layout.codes(); ++j) {
        const Vec3 c = layout.marker_centre_w(i, j);
        EXPECT_FALSE(boxes_overlap(o.x_m, o.y_m, o.bound_x_m, o.bound_y_m, c[0], c[1],
                                   layout.rect_width_m, 0.5 * layout.rect_height_m))
            << "clutter at " << o.x_m << "," << o.y_m << " over marker " << i << "," << j;
      }
}

TEST(CeilingScene, FixturePanelsStayClearOfTheMarkersAtTheirTileCorners) {
  const CeilingLayout layout;
  const CeilingScene scene(layout, 3);
  int fixtures = 0;
  for (int ti = -2; ti < layout.codes() + 2; ++ti)
    for (int tj = -2; tj < layout.codes() + 2; ++tj) {
      double he = 0, hn = 0;
      if (!scene.fixture_on_tile(ti, tj, &he, &hn)) continue;
      ++fixtures;
      const double cx = (ti + 0.5) * layout.grid_m, cy = (tj + 0.5) * layout.grid_m;
      for (int di = 0; di <= 1; ++di)
        for (int dj = 0; dj <= 1; ++dj)
          EXPECT_FALSE(boxes_overlap(cx, cy, he, hn, (ti + di) * layout.grid_m,
                                     (tj + dj) * layout.grid_m, layout.rect_width_m,
                                     0.5 * layout.rect_height_m));
    }
  // About one tile in five.
  EXPECT_GT(fixtures, 5);
  EXPECT_LT(fixtures, 60);
}

TEST(CeilingScene, RailsRunAlongGridLinesAndTilesFillTheRest) {
  const CeilingLayout layout;
  const CeilingScene scene(layout, 1);
  const double g = layout.grid_m;
  // On the line x = 2g, halfway between markers (2,1) and (2,2).
  EXPECT_EQ(scene.material_at(2 * g, 1.5 * g, false, 0), kMaterialRail);
  EXPECT_EQ(scene.material_at(2 * g + 0.6 * layout.rail_width_m, 1.5 * g, false, 0), kMaterialTile);
  // Rails continue beyond the marker grid.
  EXPECT_EQ(scene.material_at(-3 * g, 40.5 * g, false, 0), kMaterialRail);
}

TEST(CeilingScene, FixtureLayoutIsAFunctionOfTheSeed) {
  const CeilingLayout layout;
  const CeilingScene a(layout, 11), b(layout, 11), c(layout, 12);
  int same_ab = 0, same_ac = 0, tiles = 0;
  for (int ti = 0; ti < 16; ++ti)
    for (int tj = 0; tj < 16; ++tj) {
      double he = 0, hn = 0;
      const bool fa = a.fixture_on_tile(ti, tj, &he, &hn);
      same_ab += fa == b.fixture_on_tile(ti, tj, &he, &hn) ? 1 : 0;
      same_ac += fa == c.fixture_on_tile(ti, tj, &he, &hn) ? 1 : 0;
      ++tiles;
    }
  EXPECT_EQ(same_ab, tiles);
  EXPECT_LT(same_ac, tiles);
}

}  // namespace
}  // namespace ceilpose::sim
