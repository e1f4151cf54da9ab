// count_whole_markers: the denominator of availability (SPEC §6).
#include "sim/visibility.h"

#include <gtest/gtest.h>

namespace ceilpose::sim {
namespace {

TEST(Visibility, CentreOfTheGridShowsSeveralWholeMarkers) {
  SceneOptions options;
  const double g = options.layout.grid_m;
  const int n = count_whole_markers(options, {3.5 * g, 3.5 * g, 0.0}, CameraMount{});
  EXPECT_GE(n, 6);
  EXPECT_LE(n, 12);
}

TEST(Visibility, FarOutsideTheGridShowsNone) {
  SceneOptions options;
  EXPECT_EQ(count_whole_markers(options, {-5.0, -5.0, 0.3}, CameraMount{}), 0);
}

TEST(Visibility, MarkerCutByTheImageBorderIsNotWhole) {
  SceneOptions options;
  const CeilingLayout& l = options.layout;
  const CameraIntrinsics& k = options.intrinsics;
  const double m_per_px = (l.height_m - CameraMount{}.lens_height_m) / k.fx;
  // Facing East, image right is North: put marker (0, 0) at the right border.
  const double edge_m = (k.width - 1 - k.cx) * m_per_px;
  const Pose2D cut{0.0, -edge_m, 0.0};
  const Pose2D inside{0.0, -edge_m + 0.5 * l.rect_height_m + 0.01, 0.0};
  EXPECT_FALSE(marker_whole_in_view(options, camera_pose_from_robot(cut, CameraMount{}), 0, 0));
  EXPECT_TRUE(marker_whole_in_view(options, camera_pose_from_robot(inside, CameraMount{}), 0, 0));
}

TEST(Visibility, StrongDistortionDoesNotFoldFarMarkersIntoView) {
  SceneOptions options;
  options.intrinsics.distortion = {-0.35, 0.12, 0.0, 0.0, 0.0};
  EXPECT_EQ(count_whole_markers(options, {-4.0, -4.0, 0.0}, CameraMount{}), 0);
}

}  // namespace
}  // namespace ceilpose::sim
