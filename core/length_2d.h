#pragma once
#include <cmath>

namespace ceilpose {

// The length of (x, y) without std::hypot's guard against overflow and
// underflow, which costs ~54 instructions a call in glibc and is called
// ~400 times a tracked frame (pixel steps, edge normals, distances between
// markers). For the detector's and the solver's pixels, metres and
// normalised coordinates, whose squares are nowhere near a double's limits.
inline double length_2d(double x, double y) { return std::sqrt(x * x + y * y); }

}  // namespace ceilpose
