#pragma once
// A scripted path for the synthetic camera: smooth, at walking speed, over
// the marker grid, forever (it loops).
#include "core/ceiling_layout.h"
#include "core/pose.h"

namespace ceilpose::sim {

inline constexpr double kWalkingSpeed_mps = 1.2;

// Scripted smooth trajectory at walking speed over the marker grid for the synthetic camera: pose
// at time t.
Pose2D trajectory_pose(const CeilingLayout& layout, double t_s);

}  // namespace ceilpose::sim
