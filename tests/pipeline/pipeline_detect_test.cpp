// Pipeline::process() on crafted frames: headings and codes all round,
// pixel formats, lighting, bad frames, and the no-allocation promise.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "pipeline/pipeline.h"
#include "tests/pipeline/detect_scene_support.h"
#include "tests/pipeline/positioning_support.h"
#include "tests/support/alloc_count.h"

namespace ceilpose {
namespace {

double angle_difference_rad(double a, double b) {
  return std::remainder(a - b, 2.0 * std::numbers::pi);
}

std::vector<test::CraftedMarker> four_markers(double west_rad) {
  std::vector<test::CraftedMarker> m(4);
  const double u[4] = {200, 440, 200, 440}, v[4] = {150, 150, 330, 330};
  for (int k = 0; k < 4; ++k) {
    m[k].centre_u_px = u[k];
    m[k].centre_v_px = v[k];
    m[k].west_image_rad = west_rad;
    m[k].code_i = (3 * k + 1) % 8;
    m[k].code_j = (5 * k + 2) % 8;
  }
  return m;
}

// Index of the detected marker nearest (u, v), or −1.
int nearest(const FrameResult& r, double u, double v, double max_px = 3.0) {
  int best = -1;
  double best_d = max_px;
  for (int k = 0; k < r.marker_count; ++k) {
    const double d = std::hypot(r.markers[k].centre_u_px - u, r.markers[k].centre_v_px - v);
    if (d < best_d) best = k, best_d = d;
  }
  return best;
}

class PipelineDetectTest : public ::testing::Test {
 protected:
  PipelineConfig config;
  Pipeline pipeline{config};
  FrameResult result;
  void expect_all_found(const std::vector<test::CraftedMarker>& markers, const FrameResult& r,
                        const char* what) {
    EXPECT_EQ(r.marker_count, static_cast<int>(markers.size())) << what;
    for (const auto& m : markers) {
      const int k = nearest(r, m.centre_u_px, m.centre_v_px);
      ASSERT_GE(k, 0) << what << " marker at " << m.centre_u_px << "," << m.centre_v_px;
      EXPECT_EQ(r.markers[k].code_i, m.code_i) << what;
      EXPECT_EQ(r.markers[k].code_j, m.code_j) << what;
      EXPECT_TRUE(r.markers[k].whole) << what;
    }
  }
};

TEST_F(PipelineDetectTest, MarkerTurnedThroughAFullCircleKeepsHeadingCodeAndCentre) {
  const CeilingLayout& layout = config.layout;
  for (int deg = 0; deg < 360; deg += 15) {
    test::CraftedMarker m;
    // Off the pixel grid: an edge through pixel centres is a tie that the
    // classifier must break one way, a quarter-pixel shift of the centroid.
    m.centre_u_px = 320.3;
    m.centre_v_px = 240.1;
    m.west_image_rad = deg * std::numbers::pi / 180.0;
    m.code_i = 4;  // 100 and 011: reading from the wrong end gives 1 and 6
    m.code_j = 3;
    const Image image = test::render_markers(640, 480, std::span(&m, 1), layout);
    pipeline.process(image.view(), PositioningMode::kAuto, &result);
    ASSERT_EQ(result.marker_count, 1) << deg;
    const MarkerObservation& o = result.markers[0];
    EXPECT_EQ(o.code_i, 4) << deg;
    EXPECT_EQ(o.code_j, 3) << deg;
    EXPECT_NEAR(angle_difference_rad(o.west_image_rad, m.west_image_rad), 0.0, 0.003) << deg;
    EXPECT_NEAR(o.centre_u_px, m.centre_u_px, 0.3) << deg;
    EXPECT_NEAR(o.centre_v_px, m.centre_v_px, 0.3) << deg;
    // The red centre lies half a rectangle East of the marker centre.
    const double half_px = 0.5 * layout.rect_width_m * test::kDefaultPxPerM;
    EXPECT_NEAR(o.red_u_px, m.centre_u_px - half_px * std::cos(m.west_image_rad), 0.4) << deg;
    EXPECT_NEAR(o.red_v_px, m.centre_v_px - half_px * std::sin(m.west_image_rad), 0.4) << deg;
  }
}

TEST_F(PipelineDetectTest, PointsCarryTheirMarkerFrameCoordinates) {
  test::CraftedMarker m;
  const Image image = test::render_markers(640, 480, std::span(&m, 1), config.layout);
  pipeline.process(image.view(), PositioningMode::kAuto, &result);
  ASSERT_EQ(result.marker_count, 1);
  const MarkerObservation& o = result.markers[0];
  // Centre, two centroids; both ends and the two between-slot stretches of
  // the outer long side of each rectangle.
  ASSERT_EQ(o.point_count, 3 + 2 * (2 + 2));
  int edges = 0;
  for (int p = 0; p < o.point_count; ++p) {
    // Where the point should be: at yaw 0, East is image up, North right.
    const MarkerPointObservation& pt = o.points[p];
    const double du = pt.u_px - (m.centre_u_px + pt.n_m * test::kDefaultPxPerM);
    const double dv = pt.v_px - (m.centre_v_px - pt.e_m * test::kDefaultPxPerM);
    if (!pt.is_edge()) {
      EXPECT_NEAR(du, 0.0, 0.3) << p;
      EXPECT_NEAR(dv, 0.0, 0.3) << p;
      continue;
    }
    ++edges;
    // An edge point is measured across its edge, and its normal points out
    // of the rectangle: an end's along ±North (image ±u), a side's along
    // ±East (image ∓v).
    EXPECT_NEAR(du * pt.normal_u + dv * pt.normal_v, 0.0, 0.15) << p;
    const bool end = std::abs(std::abs(pt.n_m) - 0.5 * config.layout.rect_height_m) < 1e-9;
    EXPECT_NEAR(end ? pt.normal_u : -pt.normal_v,
                end ? (pt.n_m > 0 ? 1.0 : -1.0) : (pt.e_m > 0 ? 1.0 : -1.0), 1e-3)
        << p;
  }
  EXPECT_EQ(edges, 8);
}

TEST_F(PipelineDetectTest, RgbBgrYuyvAnd420FramesGiveTheSameDetections) {
  const auto markers = four_markers(0.4);
  const Image rgb = test::render_markers(640, 480, markers, config.layout);
  pipeline.process(rgb.view(), PositioningMode::kAuto, &result);
  expect_all_found(markers, result, "rgb");
  const FrameResult from_rgb = result;
  for (PixelFormat f :
       {PixelFormat::kBgr24, PixelFormat::kYuyv, PixelFormat::kNv12, PixelFormat::kYuv420}) {
    const Image converted = test::convert_rgb(rgb, f);
    pipeline.process(converted.view(), PositioningMode::kAuto, &result);
    expect_all_found(markers, result, to_string(f));
    for (int k = 0; k < from_rgb.marker_count; ++k) {
      const MarkerObservation& a = from_rgb.markers[k];
      const int j = nearest(result, a.centre_u_px, a.centre_v_px);
      ASSERT_GE(j, 0);
      EXPECT_NEAR(result.markers[j].centre_u_px, a.centre_u_px, 0.25) << to_string(f);
      EXPECT_NEAR(result.markers[j].centre_v_px, a.centre_v_px, 0.25) << to_string(f);
    }
  }
}

TEST_F(PipelineDetectTest, ExposureGainAndColourCastDoNotLoseMarkers) {
  const auto markers = four_markers(-1.1);
  const std::array<std::array<double, 3>, 7> casts{{{1.0, 1.0, 1.0},
                                                    {1.25, 1.0, 0.75},
                                                    {0.75, 1.0, 1.25},
                                                    {1.0, 1.25, 0.75},
                                                    {1.0, 0.75, 1.25},
                                                    {1.25, 0.75, 1.0},
                                                    {0.75, 1.25, 1.0}}};
  for (double gain : {0.45, 0.7, 1.0, 1.3, 1.6}) {
    for (const auto& cast : casts) {
      test::Lighting lighting{gain, cast};
      const Image image = test::render_markers(640, 480, markers, config.layout, lighting);
      pipeline.process(image.view(), PositioningMode::kAuto, &result);
      const std::string what = "gain " + std::to_string(gain) + " cast " + std::to_string(cast[0]) +
                               "," + std::to_string(cast[1]) + "," + std::to_string(cast[2]);
      expect_all_found(markers, result, what.c_str());
    }
  }
}

TEST_F(PipelineDetectTest, GreyFrameOfMarkersGivesNoMarkersAndNoPose) {
  const auto markers = four_markers(0.0);
  const Image grey = test::convert_rgb(test::render_markers(640, 480, markers, config.layout),
                                       PixelFormat::kGray8);
  pipeline.process(grey.view(), PositioningMode::kAuto, &result);
  EXPECT_EQ(result.marker_count, 0);
  EXPECT_FALSE(result.estimate.valid);
}

TEST_F(PipelineDetectTest, BadFramesGiveAnInvalidPoseWithoutCrashing) {
  std::vector<std::pair<std::string, Image>> frames;
  Image saturated(640, 480, PixelFormat::kRgb24);
  std::fill(saturated.data(), saturated.data() + saturated.size_bytes(), 255);
  frames.emplace_back("all saturated", std::move(saturated));
  frames.emplace_back("all black", Image(640, 480, PixelFormat::kRgb24));
  frames.emplace_back("wrong size", Image(320, 240, PixelFormat::kRgb24));
  Image noise(640, 480, PixelFormat::kRgb24);
  std::mt19937 rng(5);
  for (size_t i = 0; i < noise.size_bytes(); ++i) noise.data()[i] = static_cast<uint8_t>(rng());
  frames.emplace_back("random noise", std::move(noise));
  Image yuyv_noise(640, 480, PixelFormat::kYuyv);
  for (size_t i = 0; i < yuyv_noise.size_bytes(); ++i)
    yuyv_noise.data()[i] = static_cast<uint8_t>(rng());
  frames.emplace_back("random yuyv noise", std::move(yuyv_noise));
  int noisy = 0;
  for (const auto& [what, image] : frames) {
    pipeline.process(image.view(), PositioningMode::kAuto, &result);
    EXPECT_FALSE(result.estimate.valid) << what;
    EXPECT_EQ(result.marker_count, 0) << what;
    EXPECT_NE(result.estimate.refusal, Refusal::kNone) << what;
    noisy += result.noisy ? 1 : 0;
  }
  EXPECT_GE(noisy, 1);
  // Views that no camera should deliver.
  const Image good = test::render_markers(640, 480, four_markers(0.0), config.layout);
  ImageView empty{};
  ImageView null_data = good.view();
  null_data.data = nullptr;
  ImageView short_stride = good.view();
  short_stride.stride_bytes = 640;
  ImageView truncated = good.view();
  truncated.size_bytes /= 2;
  ImageView compressed = good.view();
  compressed.format = PixelFormat::kMjpeg;
  for (const ImageView& v : {empty, null_data, short_stride, truncated, compressed}) {
    pipeline.process(v, PositioningMode::kAuto, &result);
    EXPECT_FALSE(result.estimate.valid);
    EXPECT_EQ(result.marker_count, 0);
    EXPECT_EQ(result.estimate.refusal, Refusal::kUnusableFrame);
  }
}

TEST_F(PipelineDetectTest, MarkerBlurredBeyondItsRedDotsIsRefusedNotMisread) {
  // Half-size markers (3 px red dots) under 7 px of blur along North: the
  // red dots wash out, so the marker must not be decoded at all.
  PipelineConfig small = config;
  small.intrinsics = test::half_size_camera();
  Pipeline half(small);
  test::CraftedMarker m;
  m.centre_u_px = 160.3;
  m.centre_v_px = 120.2;
  m.code_i = 7;
  m.code_j = 7;
  const Image sharp = test::render_markers(320, 240, std::span(&m, 1), config.layout, {},
                                           0.5 * test::kDefaultPxPerM);
  half.process(sharp.view(), PositioningMode::kAuto, &result);
  ASSERT_EQ(result.marker_count, 1);
  const Image blurred = test::blur_rows(sharp, 7);
  half.process(blurred.view(), PositioningMode::kAuto, &result);
  EXPECT_EQ(result.marker_count, 0);
  EXPECT_EQ(result.rejects.blurred, 1);
  EXPECT_EQ(result.estimate.refusal, Refusal::kUnreadableMarkers);
}

TEST_F(PipelineDetectTest, LoneMarkerGivesAPoseOnlyWhenItsDotsReadClearly) {
  // With no other marker to check its code against, a lone marker whose
  // slots read close to the dot threshold (low quality) gives no pose; the
  // same marker among others that agree with it still counts.
  testing::SyntheticView view;
  view.intrinsics = config.intrinsics;
  view.mount = config.mount;
  view.layout = config.layout;
  std::vector<MarkerObservation> all = testing::observe(view, Pose2D{1.5, 2.1, 0.3});
  ASSERT_GE(all.size(), 3u);
  Positioner positioner(config);
  std::vector<MarkerObservation> lone{all[0]};
  lone[0].quality = 0.9f;
  EXPECT_TRUE(positioner.solve(lone, PositioningMode::kChangeOfAxes).valid);
  lone[0].quality = 0.3f;
  EXPECT_FALSE(positioner.solve(lone, PositioningMode::kChangeOfAxes).valid);
  EXPECT_FALSE(positioner.solve(lone, PositioningMode::kAuto).valid);
  all[0].quality = 0.3f;
  EXPECT_TRUE(positioner.solve(all, PositioningMode::kAuto).valid);
}

TEST_F(PipelineDetectTest, ProcessAllocatesNothing) {
  const Image image = test::render_markers(640, 480, four_markers(0.7), config.layout);
  pipeline.process(image.view(), PositioningMode::kAuto, &result);  // warm-up
  test::start_counting_allocations();
  for (int k = 0; k < 3; ++k) pipeline.process(image.view(), PositioningMode::kAuto, &result);
  EXPECT_EQ(test::stop_counting_allocations(), 0);
  EXPECT_EQ(result.marker_count, 4);
}

// Every stage runs and is timed on its own: a stage whose lap() went missing
// reads 0 and hands its time to the next one.
TEST_F(PipelineDetectTest, EveryStageIsTimedOnItsOwn) {
  const Image image = test::render_markers(640, 480, four_markers(0.2), config.layout);
  pipeline.process(image.view(), PositioningMode::kAuto, &result);
  ASSERT_EQ(result.marker_count, 4);
  int64_t sum_ns = 0;
  std::set<std::string> names;
  for (int s = 0; s < kStageCount; ++s) {
    EXPECT_GT(result.stage_ns[s], 0) << Pipeline::stage_name(s);
    sum_ns += result.stage_ns[s];
    names.insert(Pipeline::stage_name(s));
  }
  EXPECT_EQ(sum_ns, result.total_ns);
  EXPECT_EQ(names.size(), static_cast<size_t>(kStageCount)) << "each stage has its own name";
  EXPECT_EQ(names.count("unknown"), 0u);
  EXPECT_STREQ(Pipeline::stage_name(kStageReconcile), "reconcile");
  EXPECT_EQ(result.reconcile.believed + result.reconcile.rejected(), 4)
      << "every decoded marker believed or rejected for a reason";
}

TEST_F(PipelineDetectTest, NewImageSizeTakesEffectThroughSetConfig) {
  PipelineConfig small = config;
  small.intrinsics = test::half_size_camera();
  pipeline.set_config(small);
  test::CraftedMarker m;
  m.centre_u_px = 160;
  m.centre_v_px = 120;
  m.code_i = 5;
  m.code_j = 2;
  const Image image = test::render_markers(320, 240, std::span(&m, 1), config.layout, {},
                                           0.5 * test::kDefaultPxPerM);
  pipeline.process(image.view(), PositioningMode::kAuto, &result);
  ASSERT_EQ(result.marker_count, 1);
  EXPECT_EQ(result.markers[0].code_i, 5);
  EXPECT_EQ(result.markers[0].code_j, 2);
}

}  // namespace
}  // namespace ceilpose
