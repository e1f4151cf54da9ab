#include "pipeline/marker_pairing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace ceilpose {
namespace {

RectangleCandidate rect(PixelClass cls, double cx, double cy,
                        double axis_rad = 0.5 * std::numbers::pi) {
  RectangleCandidate r;
  r.cls = cls;
  r.cx = cx;
  r.cy = cy;
  r.axis_rad = axis_rad;
  r.long_px = 75.7;
  r.short_px = 31.5;
  r.area_px = 75.7 * 31.5;
  r.fill = 1.0;
  return r;
}

class MarkerPairingTest : public ::testing::Test {
 protected:
  int pair(const std::vector<RectangleCandidate>& rects) {
    return pairer.pair(rects, layout, params, out);
  }
  CeilingLayout layout;
  DetectorParams params;
  MarkerPairer pairer{32};
  std::vector<MarkerPair> out = std::vector<MarkerPair>(16);
};

TEST_F(MarkerPairingTest, RedPairsWithTheGreenSharingItsLongEdge) {
  // Green 31.5 px to the right (sharing the edge), another green far away.
  ASSERT_EQ(pair({rect(PixelClass::kRed, 100, 100), rect(PixelClass::kGreen, 131.5, 100),
                  rect(PixelClass::kGreen, 300, 100)}),
            1);
  EXPECT_EQ(out[0].red, 0);
  EXPECT_EQ(out[0].green, 1);
}

TEST_F(MarkerPairingTest, NeighbourAlongTheLongAxisIsNoPartner) {
  // Same distance, but along the long axis: end to end, not side by side.
  EXPECT_EQ(pair({rect(PixelClass::kRed, 100, 100), rect(PixelClass::kGreen, 100, 131.5)}), 0);
}

TEST_F(MarkerPairingTest, CrossedAxesAreNoPair) {
  EXPECT_EQ(pair({rect(PixelClass::kRed, 100, 100), rect(PixelClass::kGreen, 131.5, 100, 0.0)}), 0);
}

TEST_F(MarkerPairingTest, EachRectangleIsUsedOnceBestFirst) {
  // Red between two greens; the nearer-to-nominal one wins, the other red
  // keeps its own partner.
  ASSERT_EQ(pair({rect(PixelClass::kRed, 100, 100), rect(PixelClass::kGreen, 131.5, 100),
                  rect(PixelClass::kGreen, 66.0, 100), rect(PixelClass::kRed, 34.5, 100)}),
            2);
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(out[k].green, out[k].red == 0 ? 1 : 2);
  }
}

}  // namespace
}  // namespace ceilpose
