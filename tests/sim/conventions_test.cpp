// SPEC §2–3 conventions as they show in rendered frames: codes read back from
// the slot positions, red→green points West, image right is the robot's left.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>

#include "sim/renderer.h"
#include "sim/visibility.h"
#include "tests/sim/sim_test_support.h"

namespace ceilpose::sim {
namespace {

using testing::pixel;

bool is_dark(const std::array<uint8_t, 3>& p) { return std::max({p[0], p[1], p[2]}) < 90; }
bool is_red(const std::array<uint8_t, 3>& p) { return p[0] > p[1] + 80 && p[0] > p[2] + 80; }
bool is_green(const std::array<uint8_t, 3>& p) { return p[1] > p[0] + 60 && p[1] > p[2] + 40; }
bool is_saturated(const std::array<uint8_t, 3>& p) { return is_red(p) || is_green(p); }

// Reads a `bits`-bit number from the slots of one rectangle: the pixel at
// each projected slot centre, MSB from the northernmost slot.
int read_code(const Image& img, const SceneOptions& o, const CameraPose& camera, int i, int j,
              double centre_e_m) {
  const CeilingLayout& l = o.layout;
  int code = 0;
  for (int k = 0; k < l.bits; ++k) {
    const Vec3 c = l.marker_centre_w(i, j);
    double u = 0, v = 0;
    project_world_point(o.intrinsics, camera, {c[0] + centre_e_m, c[1] + l.slot_n_m(k), c[2]}, &u,
                        &v);
    code = (code << 1) |
           (is_dark(pixel(img, static_cast<int>(std::lround(u)), static_cast<int>(std::lround(v))))
                ? 1
                : 0);
  }
  return code;
}

TEST(RendererConventions, SlotsReadBackEveryCodeOfEveryMarkerInView) {
  SceneOptions options;
  Renderer renderer(options);
  const double g = options.layout.grid_m;
  std::set<int> seen_i, seen_j;
  int markers = 0;
  for (const Pose2D& robot : {Pose2D{1.5 * g, 1.5 * g, 0.3}, Pose2D{5.5 * g, 5.5 * g, 2.0},
                              Pose2D{1.5 * g, 5.5 * g, -1.2}, Pose2D{5.5 * g, 1.5 * g, 3.0}}) {
    Image img;
    renderer.render(robot, CameraMount{}, Effects{}, 1, &img);
    const CameraPose camera = camera_pose_from_robot(robot, CameraMount{});
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < 8; ++j) {
        if (!marker_whole_in_view(options, camera, i, j)) continue;
        EXPECT_EQ(read_code(img, options, camera, i, j, options.layout.red_centre_e_m()), i)
            << "red of marker " << i << "," << j;
        EXPECT_EQ(read_code(img, options, camera, i, j, options.layout.green_centre_e_m()), j)
            << "green of marker " << i << "," << j;
        seen_i.insert(i);
        seen_j.insert(j);
        ++markers;
      }
  }
  EXPECT_EQ(seen_i.size(), 8u);
  EXPECT_EQ(seen_j.size(), 8u);
  EXPECT_GT(markers, 20);
}

TEST(RendererConventions, SlotsReadBackWithAFourBitFamily) {
  // An extension of SPEC §2: four slots need taller rectangles (16 in).
  SceneOptions options;
  options.layout.bits = 4;
  options.layout.rect_height_m = 16 * kInch_m;
  Renderer renderer(options);
  const double g = options.layout.grid_m;
  std::set<int> seen_i, seen_j;
  for (int k = 0; k < 16; k += 3) {
    const Pose2D robot{(k + 0.3) * g, (15 - k + 0.2) * g, 0.25 * k};
    Image img;
    renderer.render(robot, CameraMount{}, Effects{}, 1, &img);
    const CameraPose camera = camera_pose_from_robot(robot, CameraMount{});
    for (int i = 0; i < 16; ++i)
      for (int j = 0; j < 16; ++j) {
        if (!marker_whole_in_view(options, camera, i, j)) continue;
        EXPECT_EQ(read_code(img, options, camera, i, j, options.layout.red_centre_e_m()), i);
        EXPECT_EQ(read_code(img, options, camera, i, j, options.layout.green_centre_e_m()), j);
        seen_i.insert(i);
        seen_j.insert(j);
      }
  }
  EXPECT_GE(seen_i.size(), 12u);
  EXPECT_GE(seen_j.size(), 12u);
}

struct Centroids {
  double red_u = 0, red_v = 0, green_u = 0, green_v = 0;
};

// Centroids of the red and green pixels within `radius_px` of the image centre.
Centroids colour_centroids(const Image& img, int radius_px) {
  double ru = 0, rv = 0, rn = 0, gu = 0, gv = 0, gn = 0;
  const int cu = img.width() / 2, cv = img.height() / 2;
  for (int v = cv - radius_px; v <= cv + radius_px; ++v)
    for (int u = cu - radius_px; u <= cu + radius_px; ++u) {
      const auto p = pixel(img, u, v);
      if (is_red(p)) ru += u, rv += v, rn += 1;
      if (is_green(p)) gu += u, gv += v, gn += 1;
    }
  return {ru / rn, rv / rn, gu / gn, gv / gn};
}

// Marker (0, 0) — code 0, no dots to pull the colour centroids — under the
// camera of a robot heading `yaw_rad`: the image vector from the red to the
// green rectangle's centroid.
std::array<double, 2> red_to_green_in_image(double yaw_rad) {
  SceneOptions options;
  Renderer renderer(options);
  Image img;
  renderer.render({0.0, 0.0, yaw_rad}, CameraMount{}, Effects{}, 1, &img);
  const Centroids c = colour_centroids(img, 60);
  return {c.green_u - c.red_u, c.green_v - c.red_v};
}

TEST(RendererConventions, RedToGreenPointsWestSeenFacingEast) {
  // Facing East, row 0 is East, so West is image down (+v).
  const auto d = red_to_green_in_image(0.0);
  EXPECT_GT(d[1], 20.0);
  EXPECT_LT(std::abs(d[0]), 1.0);
}

TEST(RendererConventions, RedToGreenPointsWestSeenFacingNorth) {
  // Facing North, West is the robot's left, which is image right (+u).
  const auto d = red_to_green_in_image(std::numbers::pi / 2);
  EXPECT_GT(d[0], 20.0);
  EXPECT_LT(std::abs(d[1]), 1.0);
}

TEST(RendererConventions, RedToGreenPointsWestSeenFacingWest) {
  // Facing West, West is forward: image up (-v).
  const auto d = red_to_green_in_image(std::numbers::pi);
  EXPECT_LT(d[1], -20.0);
  EXPECT_LT(std::abs(d[0]), 1.0);
}

TEST(RendererConventions, ImageRightIsTheRobotsLeft) {
  // A marker 0.2 m to the robot's left (North of a robot facing East) shows
  // right of the image centre on the centre row; 0.2 m to its right there is
  // only the rail along the robot's line.
  SceneOptions options;
  Renderer renderer(options);
  const double g = options.layout.grid_m;
  const double offset_m = 0.2;
  Image img;
  renderer.render({3 * g, 3 * g - offset_m, 0.0}, CameraMount{}, Effects{}, 1, &img);
  const CameraIntrinsics& k = options.intrinsics;
  const double du = offset_m * k.fx / (options.layout.height_m - CameraMount{}.lens_height_m);
  const int v = static_cast<int>(k.cy);
  EXPECT_TRUE(is_saturated(pixel(img, static_cast<int>(k.cx + du), v)));
  EXPECT_FALSE(is_saturated(pixel(img, static_cast<int>(k.cx - du), v)));
}

}  // namespace
}  // namespace ceilpose::sim
