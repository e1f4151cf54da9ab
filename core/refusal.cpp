#include "core/refusal.h"

namespace ceilpose {
namespace {

struct RefusalText {
  std::string_view name;
  std::string_view description;
};

constexpr std::array<RefusalText, kRefusalCount> kText{{
    {"none", "frames with a pose"},
    {"unusable_frame", "unusable frames (empty, compressed, wrong size or stride)"},
    {"noisy_frame", "frames abandoned as noise (too many colour runs)"},
    {"no_markers", "frames without a red/green rectangle pair"},
    {"unreadable_markers",
     "frames whose markers could not be read (cut by the border, blurred, ambiguous dots)"},
    {"inconsistent_markers", "frames whose markers contradict their codes or each other"},
    {"no_whole_marker", "frames without a whole marker in view"},
    {"lone_marker_unclear", "frames with one marker whose dots read unclearly"},
    {"wrong_heights",
     "frames refused because the markers' spacing contradicts the configured heights (check "
     "ceiling.height_m and mount.lens_height_m)"},
    {"too_few_markers", "frames with too few consistent markers for the positioning mode"},
    {"solver_rejected", "frames the solver rejected (no convergence or large residual)"},
    {"filter_rejected", "frames measured but refused by the temporal filter"},
    {"unmapped_markers", "frames whose whole markers are all missing from the ceiling map"},
    {"no_colour",
     "greyscale frames (the markers are found by their red and green: a colour camera or "
     "format is needed)"},
}};

}  // namespace

std::string_view refusal_name(int index) {
  if (index < 0 || index >= kRefusalCount) return "unknown";
  return kText[static_cast<size_t>(index)].name;
}

std::string_view to_string(Refusal refusal) { return refusal_name(static_cast<int>(refusal)); }

std::string_view describe(Refusal refusal) {
  const auto i = static_cast<size_t>(refusal);
  return i < kText.size() ? kText[i].description : std::string_view("frames refused (unknown)");
}

}  // namespace ceilpose
