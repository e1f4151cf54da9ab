#pragma once
// Barycentric positioning (thesis, three markers): the areal coordinates of
// the point straight above the lens within the image triangle of three
// marker centres, applied to those markers' grid positions.
#include <array>
#include <span>

#include "core/pose.h"
#include "pipeline/change_of_axes.h"
#include "pipeline/positioning_params.h"

namespace ceilpose {

// Solves from the best-conditioned triangle among the markers flagged in
// `use`. False when fewer than three markers are usable or no triangle
// reaches params.barycentric_min_area_units2; `chosen` receives the three
// fixes used. No allocation.
bool solve_barycentric(const ViewGeometry& view, const PositioningParams& params,
                       std::span<const MarkerFix> fixes, std::span<const bool> use, Pose2D* robot,
                       std::array<int, 3>* chosen);

}  // namespace ceilpose
