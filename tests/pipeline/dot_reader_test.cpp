#include "pipeline/dot_reader.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "core/pixel_read.h"
#include "pipeline/rectangle_ends.h"
#include "sim/camera_format.h"
#include "tests/pipeline/detect_scene_support.h"

namespace ceilpose {
namespace {

// The marker frame a perfect detection of `m` gives: rectangle centres and
// sides exactly as drawn.
MarkerFrame frame_of(const test::CraftedMarker& m, const CeilingLayout& layout,
                     double s = test::kDefaultPxPerM) {
  const double wu = std::cos(m.west_image_rad), wv = std::sin(m.west_image_rad);
  RectangleCandidate red, green;
  red.long_px = green.long_px = layout.rect_height_m * s;
  red.area_px = green.area_px = 1.0;
  red.axis_rad = green.axis_rad = m.west_image_rad + 0.5 * std::numbers::pi;
  const double half_px = 0.5 * layout.rect_width_m * s;
  red.cx = m.centre_u_px - half_px * wu;
  red.cy = m.centre_v_px - half_px * wv;
  green.cx = m.centre_u_px + half_px * wu;
  green.cy = m.centre_v_px + half_px * wv;
  return marker_frame(red, green, layout);
}

class DotReaderTest : public ::testing::Test {
 protected:
  CeilingLayout layout;
  DetectorParams params;
};

TEST_F(DotReaderTest, AtYawZeroNorthIsImageRightAndEastImageUp) {
  // SPEC §3 at yaw 0: Xc (image right) = North, Yc (image down) = West.
  test::CraftedMarker m;
  const MarkerFrame f = frame_of(m, layout);
  EXPECT_NEAR(f.west_image_rad, 0.5 * std::numbers::pi, 1e-12);
  EXPECT_GT(f.north_u, 0.0);
  EXPECT_NEAR(f.north_v, 0.0, 1e-9);
  EXPECT_NEAR(f.east_u, 0.0, 1e-9);
  EXPECT_LT(f.east_v, 0.0);
  EXPECT_NEAR(std::hypot(f.north_u, f.north_v), test::kDefaultPxPerM, 1e-6);
}

TEST_F(DotReaderTest, EveryCodeReadsBackMsbNorthernmost) {
  for (int i = 0; i < layout.codes(); ++i) {
    for (int j = 0; j < layout.codes(); ++j) {
      test::CraftedMarker m;
      m.centre_u_px = 160.2;
      m.centre_v_px = 119.7;
      m.code_i = i;
      m.code_j = j;
      m.west_image_rad = 0.3;
      const Image image = test::render_markers(320, 240, std::span(&m, 1), layout);
      const MarkerFrame f = frame_of(m, layout);
      const CodeReading ci =
          read_code(image.view(), f, true, layout, params, params.dot_threshold_ratio);
      const CodeReading cj =
          read_code(image.view(), f, false, layout, params, params.dot_threshold_ratio);
      ASSERT_TRUE(ci.ok && cj.ok);
      EXPECT_EQ(ci.code, i) << i << "," << j;
      EXPECT_EQ(cj.code, j) << i << "," << j;
      EXPECT_GT(std::min(ci.margin, cj.margin), 0.2f);
    }
  }
}

// YUYV frames are read with each row's pair chroma computed once
// (dot_reader.cpp): the ratios must be exactly those of the same pixels'
// RGB, as read_rgb gives it, at every sub-pixel phase and rotation. Noise
// makes every pair's chroma its own, so a pixel given its neighbour's
// would show.
TEST_F(DotReaderTest, YuyvReadsExactlyAsItsPixelsRgb) {
  std::mt19937 rng(29);
  std::uniform_int_distribution<int> noise(-25, 25);
  for (int k = 0; k < 12; ++k) {
    test::CraftedMarker m;
    m.centre_u_px = 160.0 + 0.37 * k;
    m.centre_v_px = 119.0 + 0.23 * k;
    m.code_i = (5 * k + 3) % layout.codes();
    m.code_j = (7 * k + 1) % layout.codes();
    m.west_image_rad = 0.5 * k;
    Image scene = test::render_markers(320, 240, std::span(&m, 1), layout);
    for (int y = 0; y < scene.height(); ++y) {
      for (int x = 0; x < 3 * scene.width(); ++x) {
        uint8_t& level = scene.row(y)[x];
        level = static_cast<uint8_t>(std::clamp(level + noise(rng), 0, 255));
      }
    }
    const Image yuyv = sim::convert_rgb(scene, PixelFormat::kYuyv);
    Image rgb(yuyv.width(), yuyv.height(), PixelFormat::kRgb24);
    for (int y = 0; y < rgb.height(); ++y) {
      for (int x = 0; x < rgb.width(); ++x) {
        uint8_t* p = rgb.row(y) + 3 * x;
        read_rgb(yuyv.view(), x, y, &p[0], &p[1], &p[2]);
      }
    }
    const MarkerFrame f = frame_of(m, layout);
    for (bool red : {true, false}) {
      const CodeReading a =
          read_code(yuyv.view(), f, red, layout, params, params.dot_threshold_ratio);
      const CodeReading b =
          read_code(rgb.view(), f, red, layout, params, params.dot_threshold_ratio);
      ASSERT_TRUE(a.ok && b.ok) << k;
      EXPECT_EQ(a.code, b.code) << k;
      EXPECT_EQ(a.ratio, b.ratio) << k << (red ? " red" : " green");
      EXPECT_EQ(a.margin, b.margin) << k;
    }
  }
}

// A marker frame its edges placed is within a pixel of the marker
// (Pipeline::measure_at recentres it beyond one). Read from its edges (dots
// sought ±0.25 in, one reference line a patch), every code of noisy
// markers at any rotation, the frame up to 0.7 px off either way, reads
// back with the margin a reading from centroids has, to within the noise.
TEST_F(DotReaderTest, FromEdgesReadsEveryCodeOfAFramePlacedWithinAPixel) {
  std::mt19937 rng(31);
  std::uniform_int_distribution<int> noise(-6, 6);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  float worst_margin = 1.0f, worst_margin_gap = 0.0f;
  for (int k = 0; k < 64; ++k) {
    test::CraftedMarker m;
    m.centre_u_px = 160.0 + 0.5 * unit(rng);
    m.centre_v_px = 120.0 + 0.5 * unit(rng);
    m.code_i = k % layout.codes();
    m.code_j = (k / layout.codes()) % layout.codes();
    m.west_image_rad = std::numbers::pi * unit(rng);
    Image scene = test::render_markers(320, 240, std::span(&m, 1), layout);
    for (int y = 0; y < scene.height(); ++y) {
      for (int x = 0; x < 3 * scene.width(); ++x) {
        uint8_t& level = scene.row(y)[x];
        level = static_cast<uint8_t>(std::clamp(level + noise(rng), 0, 255));
      }
    }
    MarkerFrame f = frame_of(m, layout);
    f.centre_u_px += 0.7 * unit(rng);
    f.centre_v_px += 0.7 * unit(rng);
    for (bool red : {true, false}) {
      const CodeReading edges = read_code(scene.view(), f, red, layout, params,
                                          params.dot_threshold_ratio, DotSearch::kFromEdges);
      const CodeReading centroids =
          read_code(scene.view(), f, red, layout, params, params.dot_threshold_ratio);
      ASSERT_TRUE(edges.ok && centroids.ok) << k;
      EXPECT_EQ(edges.code, red ? m.code_i : m.code_j) << k << (red ? " red" : " green");
      worst_margin = std::min(worst_margin, edges.margin);
      worst_margin_gap = std::max(worst_margin_gap, std::abs(edges.margin - centroids.margin));
    }
  }
  std::printf("[dots] from edges: smallest margin %.3f, largest gap to centroids' %.3f\n",
              worst_margin, worst_margin_gap);
  EXPECT_GT(worst_margin, 0.2f);
  EXPECT_LT(worst_margin_gap, 0.1f);
}

TEST_F(DotReaderTest, SingleDotInTheNorthSlotIsTheMostSignificantBit) {
  test::CraftedMarker m;
  m.centre_u_px = 160.2;
  m.centre_v_px = 119.7;
  m.code_i = 4;  // 100: only the northernmost slot
  m.code_j = 1;  // 001: only the southernmost
  const Image image = test::render_markers(320, 240, std::span(&m, 1), layout);
  const CodeReading ci = read_code(image.view(), frame_of(m, layout), true, layout, params,
                                   params.dot_threshold_ratio);
  ASSERT_TRUE(ci.ok);
  EXPECT_LT(ci.ratio[0], 0.5f);
  EXPECT_GT(ci.ratio[1], 0.9f);
  EXPECT_GT(ci.ratio[2], 0.9f);
}

TEST_F(DotReaderTest, MarkerReachingOutOfTheFrameIsNotRead) {
  test::CraftedMarker m;
  m.centre_u_px = 10.0;
  m.centre_v_px = 120.0;
  const Image image = test::render_markers(320, 240, std::span(&m, 1), layout);
  EXPECT_FALSE(read_code(image.view(), frame_of(m, layout), false, layout, params,
                         params.dot_threshold_ratio)
                   .ok);
}

TEST_F(DotReaderTest, EdgeSpreadGrowsWithBlurAlongNorth) {
  test::CraftedMarker m;
  m.centre_u_px = 160.2;
  m.centre_v_px = 119.7;
  const Image sharp = test::render_markers(320, 240, std::span(&m, 1), layout);
  const MarkerFrame f = frame_of(m, layout);
  const double sharp_px = edge_spread_px(sharp.view(), f, true, layout);
  ASSERT_GT(sharp_px, 0.0);
  EXPECT_LT(sharp_px, 1.0);
  const double blurred_px = edge_spread_px(test::blur_rows(sharp, 7).view(), f, true, layout);
  EXPECT_GT(blurred_px, 2.5);
  EXPECT_LT(blurred_px, 5.0);
}

// The edges a fit can tell a tilt by (rectangle_ends.h): on a turned marker
// with dots next to the ends and sides, every edge point lies the same
// distance across its edge, sharp or blurred along one image axis (the
// positioning solves that common offset: lsq_terms.h), and its normal
// points out of the rectangle.
TEST_F(DotReaderTest, EdgePointsLieAlikeAcrossTheRectanglesEdgesSharpOrBlurred) {
  test::CraftedMarker m;
  m.centre_u_px = 160.4;
  m.centre_v_px = 119.3;
  m.west_image_rad = 2.0;
  m.code_i = 7;
  m.code_j = 7;
  const Image sharp = test::render_markers(320, 240, std::span(&m, 1), layout);
  const MarkerFrame f = frame_of(m, layout);
  // Measured (px, across the edge, outwards): sharp -0.13 to -0.22, 5 px
  // box blur -0.17 to -0.29.
  for (const Image& image : {sharp, test::blur_rows(sharp, 5)}) {
    std::vector<double> across_px;
    for (bool red : {true, false}) {
      const RectangleEdges edges = measure_edges(image.view(), f, red, layout);
      ASSERT_EQ(edges.side_count, layout.bits - 1);
      std::vector<EdgeCrossing> all{edges.end[0], edges.end[1]};
      for (int k = 0; k < edges.side_count; ++k) all.push_back(edges.side[k]);
      for (const EdgeCrossing& c : all) {
        ASSERT_TRUE(c.found);
        double u = 0.0, v = 0.0;
        f.project(c.e_m, c.n_m, &u, &v);
        across_px.push_back((c.u_px - u) * c.normal_u + (c.v_px - v) * c.normal_v);
        // Outwards: away from the rectangle's centre.
        double cu = 0.0, cv = 0.0;
        f.project(red ? layout.red_centre_e_m() : layout.green_centre_e_m(), 0.0, &cu, &cv);
        EXPECT_GT((u - cu) * c.normal_u + (v - cv) * c.normal_v, 0.0);
      }
    }
    ASSERT_EQ(across_px.size(), 8u);
    double mean_px = 0.0;
    for (double a : across_px) mean_px += a / across_px.size();
    EXPECT_LT(std::abs(mean_px), 0.3);
    for (double a : across_px) EXPECT_NEAR(a, mean_px, 0.1);
  }
}

// A camera mixes a pixel's light, not its sRGB levels: render_markers
// integrates in linear light and encodes sRGB, as the simulator and a
// camera do. Moving an axis-aligned marker across the pixel grid in eighths
// of a pixel, every edge measured in linear light (EdgeLevels::kLinearLight,
// edge-tracked frames) stays where it is; on the darkest channel's levels
// (kDarkestLevel, whole sweeps) it moves with its phase.
TEST_F(DotReaderTest, LinearLightEdgesStayPutAsTheyCrossThePixelGrid) {
  // 1 in = 6 px: every edge of the axis-aligned marker then lies on a
  // boundary of render_markers' 8 x 8 sub-samples, so its coverage is exact.
  const double s = 6.0 / kInch_m;
  auto phase_spread_px = [&](EdgeLevels levels) {
    std::array<double, 8> lo, hi;
    lo.fill(INFINITY);
    hi.fill(-INFINITY);
    for (int p = 0; p < 8; ++p) {
      test::CraftedMarker m;
      m.centre_u_px = 160.0 + p / 8.0;
      m.centre_v_px = 120.0 + p / 8.0;
      const Image image = test::render_markers(320, 240, std::span(&m, 1), layout, {}, s);
      const MarkerFrame f = frame_of(m, layout, s);
      size_t k = 0;
      for (bool red : {true, false}) {
        const RectangleEdges edges = measure_edges(image.view(), f, red, layout, levels);
        EXPECT_EQ(edges.side_count, layout.bits - 1);
        std::vector<EdgeCrossing> all{edges.end[0], edges.end[1]};
        for (int i = 0; i < edges.side_count; ++i) all.push_back(edges.side[i]);
        for (const EdgeCrossing& c : all) {
          EXPECT_TRUE(c.found) << "phase " << p << "/8";
          double u = 0.0, v = 0.0;
          f.project(c.e_m, c.n_m, &u, &v);
          const double across_px = (c.u_px - u) * c.normal_u + (c.v_px - v) * c.normal_v;
          lo[k] = std::min(lo[k], across_px);
          hi[k] = std::max(hi[k], across_px);
          ++k;
        }
      }
    }
    double spread_px = 0.0;
    for (size_t k = 0; k < lo.size(); ++k) spread_px = std::max(spread_px, hi[k] - lo[k]);
    return spread_px;
  };
  const double linear_px = phase_spread_px(EdgeLevels::kLinearLight);
  const double darkest_px = phase_spread_px(EdgeLevels::kDarkestLevel);
  std::printf(
      "[edges] largest move of an edge over 8 phases: linear light %.4f px, darkest levels %.4f "
      "px\n",
      linear_px, darkest_px);
  // Measured: linear light 0.0049 px, darkest levels 0.253 px.
  EXPECT_LT(linear_px, 0.01);
  EXPECT_GT(darkest_px, 0.2);
}

// An edge whose profiles do not all find it (here the North end, beyond
// the frame's right border) gives no point rather than a lopsided one.
TEST_F(DotReaderTest, AnEdgeOutsideTheFrameGivesNoPoint) {
  test::CraftedMarker m;
  m.centre_u_px = 320.0 - 0.5 * layout.rect_height_m * test::kDefaultPxPerM - 2.0;
  m.centre_v_px = 120.0;
  const Image image = test::render_markers(320, 240, std::span(&m, 1), layout);
  const RectangleEdges edges = measure_edges(image.view(), frame_of(m, layout), true, layout);
  EXPECT_FALSE(edges.end[0].found);  // North is image right at yaw 0
  EXPECT_TRUE(edges.end[1].found);
}

TEST_F(DotReaderTest, DotThresholdRisesWithBlurRelativeToTheDot) {
  const DetectorParams d;
  const double dot_px = 6.0;
  // Sharp, and unmeasured blur: the nominal threshold.
  EXPECT_FLOAT_EQ(dot_threshold_ratio(d, 0.5, dot_px), d.dot_threshold_ratio);
  EXPECT_FLOAT_EQ(dot_threshold_ratio(d, -1.0, dot_px), d.dot_threshold_ratio);
  // Blur of most of the dot's height: fully raised, and never beyond.
  const float full = d.dot_threshold_ratio + d.dot_threshold_blur_shift;
  EXPECT_FLOAT_EQ(dot_threshold_ratio(d, d.blur_shift_full * dot_px, dot_px), full);
  EXPECT_FLOAT_EQ(dot_threshold_ratio(d, 3.0 * dot_px, dot_px), full);
  // In between it rises steadily; the same blur weighs more on a smaller dot.
  const double mid_px = 0.5 * (d.blur_shift_start + d.blur_shift_full) * dot_px;
  const float mid = dot_threshold_ratio(d, mid_px, dot_px);
  EXPECT_GT(mid, d.dot_threshold_ratio);
  EXPECT_LT(mid, full);
  EXPECT_GT(dot_threshold_ratio(d, mid_px, 0.9 * dot_px), mid);
}

TEST_F(DotReaderTest, DarkAreaBeyondTheCodesDotsIsInconsistent) {
  const double s = test::kDefaultPxPerM;
  RectangleCandidate r;
  r.area_px = layout.rect_width_m * layout.rect_height_m * s * s;
  const double red_dot_px =
      0.25 * std::numbers::pi * layout.red_dot_e_m * layout.red_dot_n_m * s * s;
  r.dark_px = 2.0 * red_dot_px;
  EXPECT_TRUE(dark_area_consistent(r, 3, true, layout, s));   // two dots: fits
  EXPECT_FALSE(dark_area_consistent(r, 0, true, layout, s));  // no dots: dirt
}

// What a tracked marker's pixels are asked for by (ask_marker_region): every
// pixel a bilinear read inside the region touches lies in its row's span,
// and the spans hold little else, at any angle, scale, and across the
// frame's borders.
TEST(MarkerRegion, SpansEveryPixelABilinearReadInsideTouchesAndLittleElse) {
  constexpr int kWidth = 640, kHeight = 480;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const double px_per_m = 100.0 + 500.0 * unit(rng);
    const double angle_rad = 2.0 * std::numbers::pi * unit(rng);
    MarkerFrame m;
    m.centre_u_px = -50.0 + (kWidth + 100.0) * unit(rng);
    m.centre_v_px = -50.0 + (kHeight + 100.0) * unit(rng);
    m.north_u = px_per_m * std::cos(angle_rad);
    m.north_v = px_per_m * std::sin(angle_rad);
    // East is North turned by −90° seen from below, as marker_frame gives.
    m.east_u = m.north_v;
    m.east_v = -m.north_u;
    const double e0_m = -0.2 + 0.3 * unit(rng), n0_m = -0.2 + 0.3 * unit(rng);
    const double e1_m = e0_m + 0.002 + 0.1 * unit(rng), n1_m = n0_m + 0.002 + 0.1 * unit(rng);
    const MarkerRegion region(m, e0_m, e1_m, n0_m, n1_m, kWidth, kHeight);
    const double step_px = 0.2;
    const double de_m = step_px / px_per_m;
    int outside = 0;
    for (double e_m = e0_m; e_m <= e1_m; e_m += de_m) {
      for (double n_m = n0_m; n_m <= n1_m; n_m += de_m) {
        double u = 0.0, v = 0.0;
        m.project(e_m, n_m, &u, &v);
        for (int dy = 0; dy <= 1; ++dy) {
          for (int dx = 0; dx <= 1; ++dx) {
            const int x = static_cast<int>(std::floor(u)) + dx;
            const int y = static_cast<int>(std::floor(v)) + dy;
            if (x < 0 || y < 0 || x >= kWidth || y >= kHeight) continue;
            const PixelSpan span =
                y >= region.first_row() && y <= region.last_row() ? region.row(y) : PixelSpan{};
            if (x < span.x0 || x > span.x1) ++outside;
          }
        }
      }
    }
    EXPECT_EQ(outside, 0) << "trial " << trial;
    // The spans: the padded region's area, and at most three pixels a row
    // of rounding (each end to a whole pixel, both ends counted).
    const double pad_m = 1.5 / px_per_m;
    const double padded_px =
        px_per_m * px_per_m * (e1_m - e0_m + 2.0 * pad_m) * (n1_m - n0_m + 2.0 * pad_m);
    double spanned_px = 0.0;
    int rows = 0;
    for (int y = region.first_row(); y <= region.last_row(); ++y) {
      const PixelSpan span = region.row(y);
      spanned_px += std::max(0, span.x1 - span.x0 + 1);
      ++rows;
    }
    EXPECT_LE(spanned_px, padded_px + 3.0 * rows) << "trial " << trial;
    // What ask_marker_region walks: the same rows, each from the same
    // column or the one before to the same or the next.
    int walked = 0, spans = 0;
    region.for_each_span([&](int y, int x0, int x1) {
      ++walked;
      const PixelSpan span = region.row(y);
      EXPECT_LE(x0, span.x0) << "trial " << trial << " row " << y;
      EXPECT_GE(x0, span.x0 - 1) << "trial " << trial << " row " << y;
      EXPECT_GE(x1, span.x1) << "trial " << trial << " row " << y;
      EXPECT_LE(x1, span.x1 + 1) << "trial " << trial << " row " << y;
    });
    for (int y = region.first_row(); y <= region.last_row(); ++y) {
      const PixelSpan span = region.row(y);
      spans += span.x0 <= span.x1 ? 1 : 0;
    }
    EXPECT_EQ(walked, spans) << "trial " << trial;
  }
}

}  // namespace
}  // namespace ceilpose
