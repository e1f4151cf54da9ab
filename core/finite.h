#pragma once
// Whether numbers are all finite: the one test behind "nothing non-finite
// reaches an output" (the localizer's estimates, the published records).
#include <algorithm>
#include <cmath>
#include <span>

namespace ceilpose {

inline bool all_finite(std::span<const double> values) {
  return std::all_of(values.begin(), values.end(), [](double x) { return std::isfinite(x); });
}

}  // namespace ceilpose
