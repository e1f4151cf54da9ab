// The printed sheets as a camera would see them: each SVG (and the PDF's
// page size) rendered by librsvg at 100 dpi, then ceilpose's own detector
// run on the picture through a virtual camera whose scale is 100 dpi on the
// ceiling. The code must decode, red must be on the left, the rectangles
// must measure their SPEC §2 sizes, and the pose must put the marker where
// the sheet says.
#include "print/marker_sheets.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "pipeline/pipeline.h"

namespace ceilpose {
namespace {

constexpr double kDpi = 100.0;
constexpr double kPxPerMm = kDpi / 25.4;

std::string temp(const std::string& name) {
  return ::testing::TempDir() + "ceilpose-sheet-" + std::to_string(getpid()) + "-" + name;
}

cv::Mat rasterise(const std::string& svg) {
  const std::string png = svg + ".png";
  const std::string cmd = "rsvg-convert --dpi-x 100 --dpi-y 100 --background-color white '" + svg +
                          "' -o '" + png + "'";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd << " (librsvg2-bin, scripts/setup)";
  cv::Mat bgr = cv::imread(png, cv::IMREAD_COLOR);
  cv::Mat rgb;
  if (!bgr.empty()) cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return rgb;
}

struct Seen {
  FrameResult result;
  double red_long_mm = 0, red_short_mm = 0, green_long_mm = 0, green_short_mm = 0;
  double red_x_px = 0, green_x_px = 0;
};

// A camera looking up at the sheet from the configured depth with 100 dpi
// on the ceiling, the robot facing North (image top), under the page centre.
Seen look(const cv::Mat& rgb, const CeilingLayout& layout) {
  PipelineConfig config;
  config.layout = layout;
  const double depth_m = layout.height_m - config.mount.lens_height_m;
  config.intrinsics.width = rgb.cols;
  config.intrinsics.height = rgb.rows;
  config.intrinsics.fx = config.intrinsics.fy = kPxPerMm * 1000.0 * depth_m;
  config.intrinsics.cx = 0.5 * (rgb.cols - 1);
  config.intrinsics.cy = 0.5 * (rgb.rows - 1);
  config.detector.min_rect_area_px = 1000;
  Pipeline pipeline(config);
  ImageView view{
      rgb.data,       rgb.cols, rgb.rows, static_cast<int>(rgb.step), PixelFormat::kRgb24,
      rgb.total() * 3};
  Seen s;
  pipeline.process(view, PositioningMode::kLeastSquares, &s.result);
  for (const RectangleCandidate& r : pipeline.rectangles()) {
    const bool red = r.cls == PixelClass::kRed;
    (red ? s.red_long_mm : s.green_long_mm) = r.long_px / kPxPerMm;
    (red ? s.red_short_mm : s.green_short_mm) = r.short_px / kPxPerMm;
    (red ? s.red_x_px : s.green_x_px) = r.cx;
  }
  return s;
}

TEST(MarkerSheet, Marker35PrintedAt100DpiReadsAsItselfAtItsSizeRedOnTheLeft) {
  const CeilingLayout layout;
  const std::string svg = temp("marker_3_5.svg");
  ASSERT_TRUE(write_marker_sheet(svg, layout, 3, 5, SheetFormat::kSvg));
  const cv::Mat rgb = rasterise(svg);
  ASSERT_FALSE(rgb.empty());
  const SheetGeometry g = marker_sheet_geometry(layout);
  EXPECT_NEAR(rgb.cols / kPxPerMm, g.page_width_mm, 0.5) << "the page is not 1:1";
  EXPECT_NEAR(rgb.rows / kPxPerMm, g.page_height_mm, 0.5);
  const Seen s = look(rgb, layout);
  ASSERT_EQ(s.result.marker_count, 1);
  EXPECT_EQ(s.result.markers[0].code_i, 3);
  EXPECT_EQ(s.result.markers[0].code_j, 5);
  EXPECT_LT(s.red_x_px, s.green_x_px) << "red must be on the left seen from below, North up";
  // SPEC §2: each rectangle 5 in x 12 in (127.0 x 304.8 mm), within 1 mm.
  EXPECT_NEAR(s.red_long_mm, 304.8, 1.0);
  EXPECT_NEAR(s.red_short_mm, 127.0, 1.0);
  EXPECT_NEAR(s.green_long_mm, 304.8, 1.0);
  EXPECT_NEAR(s.green_short_mm, 127.0, 1.0);
  // The robot under the page centre facing North sees the marker centre
  // where the sheet put it: (page centre - marker centre) North of it.
  ASSERT_TRUE(s.result.estimate.valid);
  const double north_m = (g.centre_y_mm - 0.5 * g.page_height_mm) / 1000.0;
  const double east_m = -(g.centre_x_mm - 0.5 * g.page_width_mm) / 1000.0;
  EXPECT_NEAR(s.result.estimate.pose.x_m, 3 * layout.grid_m - east_m, 0.001);
  EXPECT_NEAR(s.result.estimate.pose.y_m, 5 * layout.grid_m + north_m, 0.001);
  EXPECT_NEAR(s.result.estimate.pose.yaw_rad, std::numbers::pi / 2, 0.2 * std::numbers::pi / 180);
}

TEST(MarkerSheet, EverySheetOfTheCeilingDecodesAsItsOwnCode) {
  const CeilingLayout layout;
  for (int j = 0; j < layout.codes(); ++j)
    for (int i = 0; i < layout.codes(); ++i) {
      const std::string svg =
          temp("marker_" + std::to_string(i) + "_" + std::to_string(j) + ".svg");
      ASSERT_TRUE(write_marker_sheet(svg, layout, i, j, SheetFormat::kSvg));
      const Seen s = look(rasterise(svg), layout);
      ASSERT_EQ(s.result.marker_count, 1) << i << "," << j;
      EXPECT_EQ(s.result.markers[0].code_i, i);
      EXPECT_EQ(s.result.markers[0].code_j, j);
    }
}

TEST(MarkerSheet, PdfPagesAreTheSheetSizeInPoints) {
  const CeilingLayout layout;
  const std::string pdf = temp("marker_0_7.pdf");
  ASSERT_TRUE(write_marker_sheet(pdf, layout, 0, 7, SheetFormat::kPdf));
  std::ifstream in(pdf, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("%PDF-"), std::string::npos);
  EXPECT_NE(text.str().find("/MediaBox [ 0 0 841"), std::string::npos) << "A3 is 841.9 x 1190.6 pt";
}

TEST(CeilingPlan, ShowsEveryMarkerSeenFromBelowRedLeftOfGreen) {
  const CeilingLayout layout;
  const std::string svg = temp("layout.svg");
  ASSERT_TRUE(write_ceiling_plan(svg, layout));
  const cv::Mat rgb = rasterise(svg);
  ASSERT_FALSE(rgb.empty());
  // Seen from below with North up, East is on the left: every marker's red
  // rectangle (East of its green one) is drawn left of it.
  auto centroids = [&](cv::Scalar lo, cv::Scalar hi) {
    cv::Mat mask;
    cv::inRange(rgb, lo, hi, mask);
    std::vector<std::vector<cv::Point>> blobs;
    cv::findContours(mask, blobs, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    std::vector<cv::Point2d> out;
    for (const auto& b : blobs) {
      const cv::Moments m = cv::moments(b);
      if (m.m00 > 20) out.emplace_back(m.m10 / m.m00, m.m01 / m.m00);
    }
    return out;
  };
  const auto reds = centroids(cv::Scalar(150, 0, 0), cv::Scalar(255, 80, 80));
  const auto greens = centroids(cv::Scalar(0, 120, 30), cv::Scalar(90, 200, 110));
  ASSERT_EQ(reds.size(), 64u);
  ASSERT_EQ(greens.size(), 64u);
  for (const cv::Point2d& r : reds) {
    const cv::Point2d* nearest = &greens[0];
    for (const cv::Point2d& g : greens)
      if (cv::norm(g - r) < cv::norm(*nearest - r)) nearest = &g;
    EXPECT_GT(nearest->x, r.x) << "red right of green at " << r;
  }
}

}  // namespace
}  // namespace ceilpose
