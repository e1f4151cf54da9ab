// The least-squares tilt decision (lsq_solver.cpp, choose_tilt_model) on
// frames of the independent renderer, which shares no code with the
// simulator or the pipeline: a camera tilted 0.1–3° that the configuration
// does not know, and a level one. Each frame solved on its own; under the
// sanitizers the first fifth of the frames (accuracy_frames).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <vector>

#include "accuracy_support.h"
#include "independent_metrics_support.h"
#include "independent_renderer_support.h"
#include "pipeline/pipeline.h"
#include "sim/camera_format.h"

namespace ceilpose {
namespace {

using namespace testing::xcheck;

struct TiltRun {
  std::vector<double> errors_mm;  // frames with 6 or more markers
  int free_chosen = 0;
};

// `frames` random poses over the grid's inner part, tilted by 0.1–3° in a
// random direction (or level), read noise 2, solved by lsq alone.
TiltRun run(int frames, bool level, uint64_t seed, PixelFormat format = PixelFormat::kRgb24) {
  PipelineConfig config;
  Pipeline pipeline(config);
  FrameResult result;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  constexpr double kPi = std::numbers::pi;
  TiltRun out;
  for (int k = 0; k < frames; ++k) {
    XMount mount;
    const double tilt_rad = level ? 0.0 : (0.1 + 2.9 * u(rng)) * kPi / 180.0;
    const double dir_rad = (2.0 * u(rng) - 1.0) * kPi;
    mount.tilt_x_rad = tilt_rad * std::cos(dir_rad);
    mount.tilt_y_rad = tilt_rad * std::sin(dir_rad);
    const XPose pose{(1.5 + 4.0 * u(rng)) * kGridUnit_m, (1.5 + 4.0 * u(rng)) * kGridUnit_m,
                     (2.0 * u(rng) - 1.0) * kPi};
    XRenderOptions options;
    options.noise_sigma = 2.0;
    options.seed = static_cast<uint64_t>(k) + 1;
    const cv::Mat rgb = render_rgb(XCamera{}, mount, pose, options);
    Image image(rgb.cols, rgb.rows, PixelFormat::kRgb24);
    for (int y = 0; y < rgb.rows; ++y)
      std::memcpy(image.data() + y * image.stride_bytes(), rgb.ptr(y), 3 * size_t(rgb.cols));
    if (format != PixelFormat::kRgb24) image = sim::convert_rgb(image, format);
    pipeline.process(image.view(), PositioningMode::kLeastSquares, &result);
    const PoseEstimate& e = result.estimate;
    if (!e.valid || e.markers < 6) continue;
    out.errors_mm.push_back(1e3 * std::hypot(e.pose.x_m - pose.x_m, e.pose.y_m - pose.y_m));
    out.free_chosen += pipeline.positioner().last_lsq().tilt_choice == TiltChoice::kFreeFits;
  }
  std::sort(out.errors_mm.begin(), out.errors_mm.end());
  return out;
}

double p99(const std::vector<double>& sorted) {
  return sorted[std::min(sorted.size() - 1, static_cast<size_t>(0.99 * sorted.size()))];
}

// Issue 25's limit: p99 <= 2 mm on tilted frames with 6 or more markers.
// History on these 150 frames: 6.0 mm with the old decision (chi2 > 100
// alone: tilts of 0.13-0.19 deg held at level); 2.21 mm once the decision
// weighed the shift, where three collinear points a marker left the free
// fit's own sigma at ~3 mm; measured 2026-12-04 with the rectangles' edge
// points (rectangle_ends.h): p99 1.24 mm, max 1.31 mm.
TEST(TiltDecision, ATiltedCameraWithSixOrMoreMarkersIsNotHeldAtLevel) {
  const int frames = testing::accuracy_frames(150);
  const TiltRun r = run(frames, false, 5);
  ASSERT_GE(r.errors_mm.size(), static_cast<size_t>(frames * 2 / 3));
  EXPECT_LE(p99(r.errors_mm), 1.8);
  EXPECT_LE(r.errors_mm.back(), 2.2);
  EXPECT_GE(r.free_chosen, static_cast<int>(r.errors_mm.size()) * 9 / 10);
}

// The same through a Pi camera's 4:2:0 chroma (NV12), another seed.
// Measured: p99 1.78 mm, max 1.86 mm.
TEST(TiltDecision, ATiltedNv12CameraWithSixOrMoreMarkersIsNotHeldAtLevel) {
  const int frames = testing::accuracy_frames(150);
  const TiltRun r = run(frames, false, 7, PixelFormat::kNv12);
  ASSERT_GE(r.errors_mm.size(), static_cast<size_t>(frames * 2 / 3));
  EXPECT_LE(p99(r.errors_mm), 2.0);
  EXPECT_LE(r.errors_mm.back(), 2.5);
}

// The other side of the decision: a level camera must not "find" tilts.
// Measured: no frame of 150 chose the free tilt, p99 0.31 mm (0.50 mm before
// the edge points).
TEST(TiltDecision, ALevelCameraKeepsTheTiltHeld) {
  const int frames = testing::accuracy_frames(150);
  const TiltRun r = run(frames, true, 5);
  ASSERT_GE(r.errors_mm.size(), static_cast<size_t>(frames * 2 / 3));
  EXPECT_LE(r.free_chosen, 1);
  EXPECT_LE(p99(r.errors_mm), 0.5);
}

}  // namespace
}  // namespace ceilpose
