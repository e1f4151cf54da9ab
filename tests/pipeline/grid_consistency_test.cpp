#include "pipeline/grid_consistency.h"

#include <gtest/gtest.h>

#include <array>

#include "pipeline/pipeline_config.h"
#include "positioning_support.h"

namespace ceilpose {
namespace {

TEST(GridConsistency, KeepsAllMarkersOfAConsistentView) {
  PipelineConfig config;
  const ViewGeometry view(config);
  testing::SyntheticView sv;
  const auto fixes = testing::fixes_of(view, testing::observe(sv, {2.0, 2.0, 0.4}));
  ASSERT_GE(fixes.size(), 4u);
  std::array<bool, kMaxMarkersPerFrame> inlier{};
  EXPECT_EQ(grid_consistent_subset(config.positioning, config.layout.grid_m, fixes, inlier),
            static_cast<int>(fixes.size()));
}

TEST(GridConsistency, RejectsMarkerWithMisreadCode) {
  PipelineConfig config;
  const ViewGeometry view(config);
  testing::SyntheticView sv;
  auto markers = testing::observe(sv, {2.0, 2.0, 0.4});
  ASSERT_GE(markers.size(), 4u);
  markers[1].code_i ^= 1;  // one misread bit
  const auto fixes = testing::fixes_of(view, markers);
  std::array<bool, kMaxMarkersPerFrame> inlier{};
  EXPECT_EQ(grid_consistent_subset(config.positioning, config.layout.grid_m, fixes, inlier),
            static_cast<int>(fixes.size()) - 1);
  EXPECT_FALSE(inlier[1]);
  EXPECT_TRUE(inlier[0]);
}

TEST(GridConsistency, RefusesTwoMarkersThatDisagree) {
  PipelineConfig config;
  const ViewGeometry view(config);
  testing::SyntheticView sv;
  auto markers = testing::observe(sv, {2.0, 2.0, 0.4});
  markers.resize(2);
  markers[1].code_j ^= 2;
  const auto fixes = testing::fixes_of(view, markers);
  std::array<bool, kMaxMarkersPerFrame> inlier{};
  EXPECT_EQ(grid_consistent_subset(config.positioning, config.layout.grid_m, fixes, inlier), 0);
}

TEST(GridConsistency, AcceptsASingleMarker) {
  PipelineConfig config;
  const ViewGeometry view(config);
  testing::SyntheticView sv;
  auto markers = testing::observe(sv, {2.0, 2.0, 0.4});
  markers.resize(1);
  const auto fixes = testing::fixes_of(view, markers);
  std::array<bool, kMaxMarkersPerFrame> inlier{};
  EXPECT_EQ(grid_consistent_subset(config.positioning, config.layout.grid_m, fixes, inlier), 1);
}

}  // namespace
}  // namespace ceilpose
