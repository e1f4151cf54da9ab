#pragma once
// The straight edges of a marker's rectangles, found by profiles across
// them: the short ends (n = ±6 in), whose sharpness is the blur that sets
// the dot threshold, and the outer long sides (e = ±5 in) between the dot
// slots. Where each edge lies is an edge point for positioning.
//
// Why edges: the rectangle centroids are collinear (n = 0), so they tell a
// tilted camera from a shifted one only through the spread of the markers
// over the image. The edges lie around them, their images are straight with
// the tile's full contrast, and a blurred step's half-way level lies on the
// edge whatever a symmetric blur's width.
#include <array>

#include "core/ceiling_layout.h"
#include "core/image.h"
#include "pipeline/dot_reader.h"

namespace ceilpose {

// Each profile runs from this far inside its edge to as far outside it: an
// edge more than about half of it from where the profile was placed is not
// measured truly (edge-tracked frames place them by a prediction).
inline constexpr double kEdgeProfileHalf_m = 1.0 * kInch_m;

struct EdgeCrossing {
  bool found = false;
  // The marker point (e_m, n_m) on the edge and its image, distorted
  // pixels (the mean over the parallel profiles that crossed it), and the
  // image direction across the edge, unit, outwards.
  double e_m = 0.0, n_m = 0.0;
  double u_px = 0.0, v_px = 0.0;
  double normal_u = 0.0, normal_v = 0.0;
};

inline constexpr int kMaxSideCrossings = kMaxBits;

struct RectangleEdges {
  std::array<EdgeCrossing, 2> end{};  // North end (n > 0), South end
  // The outer long side, half-way between neighbouring slots.
  std::array<EdgeCrossing, kMaxSideCrossings> side{};
  int side_count = 0;
  // Blur along North at the ends, pixels (mean over the profiles that
  // measured one): the distance over which the darkest channel climbs from
  // 25 % to 75 % of the way from the rectangle's level to the tile's.
  // Negative: not measured.
  double spread_px = -1.0;
};

// What an edge's position is measured in.
enum class EdgeLevels {
  // The darkest channel's 8-bit levels, two profiles an edge: what a whole
  // sweep's fit weighs against the rectangles' centroids (and was tuned with).
  kDarkestLevel,
  // Linear light of one channel the rectangle prints dark in, the same on both
  // sides of the edge (green for red, red for green; luma in YUV and in RGB
  // decoded from a subsampled JPEG, ImageView::chroma_halved, whose chroma
  // has half the resolution), four profiles an edge, a sample per
  // pixel along the image axis the profile runs closest to: what an
  // edge-tracked frame positions with alone. docs/decisions.md "Edges in
  // linear light".
  kLinearLight,
};

// The edges of the red (x code) or green (y code) rectangle of `marker`.
// Sparse reads of the frame: no allocation.
RectangleEdges measure_edges(const ImageView& frame, const MarkerFrame& marker, bool red,
                             const CeilingLayout& layout,
                             EdgeLevels levels = EdgeLevels::kDarkestLevel);

// Blur along North at the rectangle's two short ends, in pixels
// (measure_edges().spread_px): 0.5 px for a sharp edge, 1.35 σ for
// Gaussian blur, half the length of motion blur along North; negative when
// it cannot be measured (an end outside the frame, too little contrast).
double edge_spread_px(const ImageView& frame, const MarkerFrame& marker, bool red,
                      const CeilingLayout& layout);

}  // namespace ceilpose
