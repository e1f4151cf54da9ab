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

namespace ceilpose::sim {

inline constexpr double kDriveMinSpeed_mps = 0.1;
inline constexpr double kDriveMaxSpeed_mps = 1.5;
inline constexpr double kDriveSpeedPeriod_s = 9.0;

// A curving drive for the moving-robot tests (the `drive` set): a closed
// path of smooth curves (radius 0.35 m and up) around the grid centre, heading
// along the path, speed swinging smoothly between 0.1 and 1.5 m/s. Pose at
// time t; it loops.
Pose2D drive_pose(const CeilingLayout& layout, double t_s);

}  // namespace ceilpose::sim
