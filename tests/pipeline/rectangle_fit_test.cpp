#include "pipeline/rectangle_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace ceilpose {
namespace {

// A component with the moments of a filled w × h rectangle (axis-aligned,
// long side along v), as the labeler would report it.
Component rectangle_component(PixelClass cls, double w_px, double h_px, double area_scale = 1.0) {
  Component c;
  c.cls = cls;
  c.area_px = static_cast<int>(std::lround(w_px * h_px * area_scale));
  c.cx = 100.0;
  c.cy = 80.0;
  c.mu20 = (w_px * w_px - 1.0) / 12.0;
  c.mu02 = (h_px * h_px - 1.0) / 12.0;
  c.mu11 = 0.0;
  return c;
}

class RectangleFitTest : public ::testing::Test {
 protected:
  CeilingLayout layout;
  DetectorParams params;
  RectangleModel model = make_rectangle_model(CameraIntrinsics{}, CameraMount{}, layout);
  std::vector<RectangleCandidate> out = std::vector<RectangleCandidate>(8);
  int fit(const Component& c) { return fit_rectangles(std::span(&c, 1), model, params, out); }
};

TEST_F(RectangleFitTest, ModelPredictsTheSpecMarkerSize) {
  // SPEC §3: a marker is about 63 × 76 px at the default heights.
  EXPECT_NEAR(2.0 * model.expected_short_px, 63.0, 1.0);
  EXPECT_NEAR(model.expected_long_px, 76.0, 1.0);
}

TEST_F(RectangleFitTest, MarkerRectangleIsAcceptedWithItsSides) {
  ASSERT_EQ(fit(rectangle_component(PixelClass::kRed, 31.5, 75.7)), 1);
  EXPECT_NEAR(out[0].long_px, 75.7, 0.1);
  EXPECT_NEAR(out[0].short_px, 31.5, 0.1);
  EXPECT_NEAR(std::abs(out[0].axis_rad), 0.5 * 3.14159265, 1e-6);
  EXPECT_NEAR(out[0].fill, 1.0, 0.01);
}

TEST_F(RectangleFitTest, SquareIsRejectedByAspect) {
  EXPECT_EQ(fit(rectangle_component(PixelClass::kGreen, 49.0, 49.0)), 0);
}

TEST_F(RectangleFitTest, TooSmallOrTooLargeIsRejectedByArea) {
  EXPECT_EQ(fit(rectangle_component(PixelClass::kRed, 15.0, 36.0)), 0);
  EXPECT_EQ(fit(rectangle_component(PixelClass::kRed, 50.0, 120.0)), 0);
}

TEST_F(RectangleFitTest, SparseShapeIsRejectedByFill) {
  // Same moments as the marker rectangle, two thirds of its pixels (a ring
  // or an L-shape).
  EXPECT_EQ(fit(rectangle_component(PixelClass::kRed, 31.5, 75.7, 0.66)), 0);
}

TEST_F(RectangleFitTest, DarkComponentsAreNotRectangles) {
  EXPECT_EQ(fit(rectangle_component(PixelClass::kDark, 31.5, 75.7)), 0);
}

}  // namespace
}  // namespace ceilpose
