#include "core/positioning_mode.h"

namespace ceilpose {

std::string_view to_string(PositioningMode mode) {
  switch (mode) {
    case PositioningMode::kAuto:
      return "auto";
    case PositioningMode::kChangeOfAxes:
      return "axes";
    case PositioningMode::kBarycentric:
      return "barycentric";
    case PositioningMode::kLeastSquares:
      return "lsq";
  }
  return "unknown";
}

bool positions_from_centroids(PositioningMode mode) {
  return mode == PositioningMode::kChangeOfAxes || mode == PositioningMode::kBarycentric;
}

bool parse_positioning_mode(std::string_view text, PositioningMode* mode) {
  for (auto m : kPositioningModes) {
    if (text == to_string(m)) {
      *mode = m;
      return true;
    }
  }
  return false;
}

std::vector<std::string> positioning_mode_names() {
  std::vector<std::string> names;
  for (auto m : kPositioningModes) names.emplace_back(to_string(m));
  return names;
}

std::string positioning_mode_list() {
  std::string list;
  for (size_t i = 0; i < kPositioningModes.size(); ++i) {
    if (i > 0) list += i + 1 == kPositioningModes.size() ? " or " : ", ";
    list += to_string(kPositioningModes[i]);
  }
  return list;
}

}  // namespace ceilpose
