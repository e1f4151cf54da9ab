#include "pipeline/pose_estimate.h"

namespace ceilpose {

std::string_view to_string(PositioningMode mode) {
  switch (mode) {
    case PositioningMode::kAuto: return "auto";
    case PositioningMode::kChangeOfAxes: return "axes";
    case PositioningMode::kBarycentric: return "barycentric";
    case PositioningMode::kLeastSquares: return "lsq";
  }
  return "unknown";
}

bool parse_positioning_mode(std::string_view text, PositioningMode* mode) {
  for (auto m : {PositioningMode::kAuto, PositioningMode::kChangeOfAxes,
                 PositioningMode::kBarycentric, PositioningMode::kLeastSquares}) {
    if (text == to_string(m)) {
      *mode = m;
      return true;
    }
  }
  return false;
}

}  // namespace ceilpose
