#pragma once
// Which markers a camera sees whole (SPEC §6: "at least one whole marker —
// its entire outline inside the image — is in view"), the denominator of
// availability.
#include <array>

#include "core/camera_model.h"
#include "core/ceiling_layout.h"
#include "core/pose.h"
#include "sim/renderer.h"

namespace ceilpose::sim {

// Corners of marker (i, j)'s outline in the world: NE, NW, SW, SE.
std::array<Vec3, 4> marker_outline_w(const CeilingLayout& layout, int i, int j);

// Whether the entire outline of marker (i, j) projects inside the image.
bool marker_whole_in_view(const SceneOptions& options, const CameraPose& camera, int i, int j);

// Markers whose entire outline projects inside the image (SPEC §6 "whole marker in view").
int count_whole_markers(const SceneOptions& options, const Pose2D& robot, const CameraMount& mount);

}  // namespace ceilpose::sim
