#pragma once
// Parameters of the detection stages (colour classification .. dot reading).
// Owned by the detection stages; every field: meaning, unit, cost, when to tune.
namespace ceilpose {

struct DetectorParams {
  int min_rect_area_px = 150;  // smallest rectangle blob accepted, pixels
};

}  // namespace ceilpose
