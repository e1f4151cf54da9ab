// Each photometric effect does what it says, measured on rendered frames
// against the same frame rendered clean.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/renderer.h"
#include "tests/sim/sim_test_support.h"

namespace ceilpose::sim {
namespace {

using testing::pixel;

// A view of tile with no fixture and no marker near the centre: the robot
// stands in a tile centre. Fixtures are switched off unless a test wants them.
class EffectsTest : public ::testing::Test {
 protected:
  EffectsTest() : renderer_(options_) {}

  Image render(const Effects& e, uint64_t frame_seed = 3) {
    Image img;
    renderer_.render(robot_, CameraMount{}, e, frame_seed, &img);
    return img;
  }
  static Effects no_fixtures() {
    Effects e;
    e.light_fixtures = false;
    return e;
  }
  // Mean and standard deviation of (a - b) over channel c of a central
  // 40x40 window, which sees only tile.
  static void diff_stats(const Image& a, const Image& b, int c, double* mean, double* sd) {
    double s = 0, s2 = 0, n = 0;
    for (int v = 220; v < 260; ++v)
      for (int u = 300; u < 340; ++u) {
        const double d = pixel(a, u, v)[c] - static_cast<double>(pixel(b, u, v)[c]);
        s += d;
        s2 += d * d;
        n += 1;
      }
    *mean = s / n;
    *sd = std::sqrt(s2 / n - (s / n) * (s / n));
  }
  double linear_at_centre(const Image& img, int c) const {
    return srgb_to_linear(pixel(img, 320, 240)[c]);
  }

  SceneOptions options_;
  Renderer renderer_;
  Pose2D robot_{2.5 * options_.layout.grid_m, 2.5 * options_.layout.grid_m, 0.4};
};

TEST_F(EffectsTest, CentreWindowSeesPlainTile) {
  const Image img = render(no_fixtures());
  const Rgb tile = options_.layout.tile;
  for (int v = 220; v < 260; ++v)
    for (int u = 300; u < 340; ++u) {
      ASSERT_EQ(pixel(img, u, v)[0], tile.r);
      ASSERT_EQ(pixel(img, u, v)[2], tile.b);
    }
}

TEST_F(EffectsTest, GainScalesLinearRadiance) {
  Effects e = no_fixtures();
  e.gain = 0.5;
  const Image dim = render(e), clean = render(no_fixtures());
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(linear_at_centre(dim, c) / linear_at_centre(clean, c), 0.5, 0.02);
}

TEST_F(EffectsTest, ColourCastMultipliesEachChannel) {
  Effects e = no_fixtures();
  e.white_balance = {1.15, 1.0, 0.75};
  const Image cast = render(e), clean = render(no_fixtures());
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(linear_at_centre(cast, c) / linear_at_centre(clean, c), e.white_balance[c], 0.02);
}

TEST_F(EffectsTest, GradientBrightensAlongItsDirection) {
  Effects e = no_fixtures();
  e.gradient_amplitude = 0.5;
  e.gradient_angle_rad = 0.0;  // brighter towards image right
  const Image img = render(e), clean = render(no_fixtures());
  // Compare like with like: the same pixels, with and without the gradient.
  auto ratio = [&](int u) {
    return srgb_to_linear(pixel(img, u, 240)[1]) / srgb_to_linear(pixel(clean, u, 240)[1]);
  };
  EXPECT_LT(ratio(300), 1.0);
  EXPECT_GT(ratio(339), ratio(300) + 0.02);
}

TEST_F(EffectsTest, ReadNoiseHasTheRequestedSigma) {
  Effects e = no_fixtures();
  e.read_noise_sigma = 4.0;
  const Image noisy = render(e), clean = render(no_fixtures());
  for (int c = 0; c < 3; ++c) {
    double mean = 0, sd = 0;
    diff_stats(noisy, clean, c, &mean, &sd);
    EXPECT_NEAR(sd, 4.0, 0.4);
    EXPECT_NEAR(mean, 0.0, 0.5);
  }
}

TEST_F(EffectsTest, ShotNoiseVarianceIsScaleTimesLevel) {
  Effects e = no_fixtures();
  e.shot_noise_scale = 0.2;
  const Image noisy = render(e), clean = render(no_fixtures());
  double mean = 0, sd = 0;
  diff_stats(noisy, clean, 0, &mean, &sd);
  EXPECT_NEAR(sd, std::sqrt(0.2 * options_.layout.tile.r), 0.6);
}

TEST_F(EffectsTest, NoiseDiffersBetweenFrameSeeds) {
  Effects e = no_fixtures();
  e.read_noise_sigma = 3.0;
  const Image a = render(e, 1), b = render(e, 2);
  double mean = 0, sd = 0;
  diff_stats(a, b, 1, &mean, &sd);
  EXPECT_NEAR(sd, 3.0 * std::sqrt(2.0), 0.5);
}

// Sum of squared differences between horizontal / vertical neighbours (total
// variation would not do: blurring a monotone edge keeps it).
double edge_energy(const Image& img, bool horizontal) {
  double s = 0;
  for (int v = 1; v < img.height(); ++v)
    for (int u = 1; u < img.width(); ++u) {
      const int a = pixel(img, u, v)[1];
      const int b = horizontal ? pixel(img, u - 1, v)[1] : pixel(img, u, v - 1)[1];
      s += (a - b) * (a - b);
    }
  return s;
}

TEST_F(EffectsTest, DefocusBlurSoftensEdges) {
  Effects e = no_fixtures();
  e.defocus_sigma_px = 2.0;
  const Image blurred = render(e), clean = render(no_fixtures());
  EXPECT_LT(edge_energy(blurred, true), 0.8 * edge_energy(clean, true));
}

TEST_F(EffectsTest, MotionBlurSmearsAlongItsDirectionOnly) {
  robot_.yaw_rad = 0.0;  // rails and marker edges run along the image axes
  Effects e = no_fixtures();
  e.motion_blur_px = 8.0;
  e.motion_blur_angle_rad = 0.0;  // along image rows
  const Image smeared = render(e), clean = render(no_fixtures());
  const double h_ratio = edge_energy(smeared, true) / edge_energy(clean, true);
  const double v_ratio = edge_energy(smeared, false) / edge_energy(clean, false);
  // Edges across the motion lose most of their energy; edges along it keep
  // most of theirs (dot outlines and corners lose some).
  EXPECT_LT(h_ratio, 0.4);
  EXPECT_GT(v_ratio, 0.75);
}

TEST_F(EffectsTest, JpegRoundTripAltersPixelsSlightly) {
  Effects e = no_fixtures();
  e.jpeg_quality = 60;
  const Image jpeg = render(e), clean = render(no_fixtures());
  double diff = 0;
  for (size_t i = 0; i < clean.size_bytes(); ++i)
    diff += std::abs(jpeg.data()[i] - static_cast<int>(clean.data()[i]));
  diff /= static_cast<double>(clean.size_bytes());
  EXPECT_GT(diff, 0.2);
  EXPECT_LT(diff, 6.0);
}

// Pixels where `pred(pixel of a, pixel of b)` holds.
template <typename Pred>
int count_pixels(const Image& a, const Image& b, Pred pred) {
  int n = 0;
  for (int v = 0; v < a.height(); ++v)
    for (int u = 0; u < a.width(); ++u) n += pred(pixel(a, u, v), pixel(b, u, v)) ? 1 : 0;
  return n;
}

int count_white(const Image& img) {
  return count_pixels(img, img, [](const auto& p, const auto&) {
    return p[0] == 255 && p[1] == 255 && p[2] == 255;
  });
}

// A robot standing under the centre of a tile that holds a light panel.
Pose2D under_a_fixture(const CeilingScene& scene) {
  const double g = scene.layout().grid_m;
  for (int tj = 0; tj < 8; ++tj)
    for (int ti = 0; ti < 8; ++ti) {
      double he = 0, hn = 0;
      if (scene.fixture_on_tile(ti, tj, &he, &hn)) return {(ti + 0.5) * g, (tj + 0.5) * g, 0.0};
    }
  ADD_FAILURE() << "no fixture on the 8x8 grid's tiles";
  return {};
}

TEST_F(EffectsTest, FixturesSaturateAndCanBeSwitchedOff) {
  robot_ = under_a_fixture(renderer_.scene());
  const Image lit = render(Effects{}), dark = render(no_fixtures());
  EXPECT_GT(count_white(lit), 2000);
  EXPECT_EQ(count_white(dark), 0);
}

TEST_F(EffectsTest, BloomBrightensTheSurroundingsOfFixtures) {
  robot_ = under_a_fixture(renderer_.scene());
  Effects e;
  e.bloom = 1.0;
  const Image bloomed = render(e), plain = render(Effects{});
  EXPECT_GT(count_white(bloomed), count_white(plain));
  long sum_b = 0, sum_p = 0;
  for (size_t i = 0; i < plain.size_bytes(); ++i) {
    sum_b += bloomed.data()[i];
    sum_p += plain.data()[i];
  }
  EXPECT_GT(sum_b, sum_p);
}

TEST_F(EffectsTest, OccluderCoversAboutTheRequestedFraction) {
  Effects e = no_fixtures();
  e.occlusion_fraction = 0.2;
  const Image occluded = render(e), clean = render(no_fixtures());
  const int changed = count_pixels(occluded, clean, [](const auto& a, const auto& b) {
    return a[0] < 50 && a[1] < 50 && a[2] < 50 && a != b;
  });
  const double fraction = static_cast<double>(changed) / (occluded.width() * occluded.height());
  // The blob may reach past the image border and hides dark dots unchanged.
  EXPECT_GT(fraction, 0.12);
  EXPECT_LT(fraction, 0.23);
}

TEST_F(EffectsTest, ClutterObjectAppearsWhereTheSceneSaysAndOnlyWhenEnabled) {
  const ClutterObject& o = renderer_.scene().clutter()[0];
  robot_ = {o.x_m, o.y_m, 0.0};  // the optical axis meets the ceiling at the object's centre
  Effects e = no_fixtures();
  e.clutter_objects = 1;
  const Image with = render(e), without = render(no_fixtures());
  const auto p = pixel(with, 320, 240);  // centre pixel (319.5, 239.5) +- 0.5
  EXPECT_EQ(p[0], o.colour.r);
  EXPECT_EQ(p[1], o.colour.g);
  EXPECT_EQ(p[2], o.colour.b);
  EXPECT_NE(pixel(without, 320, 240), p);
}

}  // namespace
}  // namespace ceilpose::sim
