#pragma once
// What marker recognition hands to positioning: one decoded marker with image
// points whose positions in the marker's own frame are known. This is the
// seam between the detection stages and the positioning stages.
#include <array>
#include <cstdint>

namespace ceilpose {

// One correspondence: a point of the marker (marker frame, e East, n North,
// origin at the marker centre, metres) and where it was measured in the
// image (distorted pixel coordinates, as in the frame). An edge point
// (normal ≠ 0) was found on the image of a straight edge of the marker
// through (e, n), by a search across it: only its distance across the edge
// is measured (along (normal_u, normal_v), a unit image direction), so a
// solve uses its residual in that direction alone.
struct MarkerPointObservation {
  double e_m = 0.0;
  double n_m = 0.0;
  double u_px = 0.0;
  double v_px = 0.0;
  double normal_u = 0.0;
  double normal_v = 0.0;
  bool is_edge() const { return normal_u != 0.0 || normal_v != 0.0; }
};

inline constexpr int kMaxPointsPerMarker = 24;
inline constexpr int kMaxMarkersPerFrame = 64;

struct MarkerObservation {
  int code_i = 0;  // grid x code (red rectangle)
  int code_j = 0;  // grid y code (green rectangle)
  // Image of the marker centre (midpoint of the shared edge), pixels.
  double centre_u_px = 0.0;
  double centre_v_px = 0.0;
  // Images of the red and green rectangle centres, pixels.
  double red_u_px = 0.0;
  double red_v_px = 0.0;
  double green_u_px = 0.0;
  double green_v_px = 0.0;
  // Image angle of the red→green vector, atan2(dv, du): the direction of
  // world West as seen in the image.
  double west_image_rad = 0.0;
  bool whole = true;     // the entire outline lies inside the image
  float quality = 1.0f;  // 0..1, fit quality (template fill, dot contrast)
  int point_count = 0;
  std::array<MarkerPointObservation, kMaxPointsPerMarker> points{};
};

}  // namespace ceilpose
