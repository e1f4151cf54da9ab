#pragma once
// Robust rejection of markers whose code disagrees with the others': every
// marker, through Change of Axes, implies where the camera is; a correctly
// decoded set agrees, a misread bit moves one marker's answer by a whole grid
// unit or more.
#include <span>

#include "pipeline/change_of_axes.h"
#include "pipeline/positioning_params.h"

namespace ceilpose {

// Marks in `inlier` (same length as `fixes`) the largest set of markers that
// agree on the camera position and heading within the tolerances of
// `params`, and returns its size. Returns 0 (no inliers) when two different
// sets are equally large: with no majority no marker can be trusted.
// No allocation; O(n²) in the number of markers.
int grid_consistent_subset(const PositioningParams& params, double grid_m,
                           std::span<const MarkerFix> fixes, std::span<bool> inlier);

}  // namespace ceilpose
