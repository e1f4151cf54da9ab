#pragma once
// Whether the robot has a fix, as the localizer decides it and as the
// shared-memory status (ceilpose_status.fix_state, whose C constants must
// equal these values) and `ceilposectl status` report it.
#include <cstdint>

namespace ceilpose {

enum class FixState : uint32_t {
  kNone = 0,      // no pose since start
  kOk = 1,        // the last frame gave a pose
  kCoasting = 2,  // recent fix, current poses predicted by the filter
  kLost = 3,      // no fix for longer than the filter coasts
};

inline const char* to_string(FixState state) {
  switch (state) {
    case FixState::kNone:
      return "none";
    case FixState::kOk:
      return "fix";
    case FixState::kCoasting:
      return "coasting";
    case FixState::kLost:
      return "lost";
  }
  return "unknown";
}

}  // namespace ceilpose
