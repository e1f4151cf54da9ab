#pragma once
// Unit conversions written once.
#include <numbers>

namespace ceilpose {

inline constexpr double kDegPerRad = 180.0 / std::numbers::pi;
inline constexpr double kRadPerDeg = std::numbers::pi / 180.0;

}  // namespace ceilpose
