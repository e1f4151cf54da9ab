#pragma once

// Floor and ceiling to int where the hot paths need them: x86-64's baseline
// (SSE2) has no rounding instruction, and std::floor becomes a sequence of
// a dozen instructions per call (a tracked frame calls it ~10 000 times).
// The same result as static_cast<int>(std::floor(x)) for any x whose floor
// is an int; like it, x must be so (callers clamp or bound it first).

namespace ceilpose {

inline int floor_int(double x) {
  const int i = static_cast<int>(x);  // towards zero
  return i - (x < i ? 1 : 0);
}

inline int ceil_int(double x) {
  const int i = static_cast<int>(x);
  return i + (x > i ? 1 : 0);
}

}  // namespace ceilpose
