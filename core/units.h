#pragma once
// Unit conversions written once.
#include <numbers>

namespace ceilpose {

inline constexpr double kDegPerRad = 180.0 / std::numbers::pi;

}  // namespace ceilpose
