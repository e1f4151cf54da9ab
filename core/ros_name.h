#pragma once
// The robot name is a ROS 2 name token (the namespace of its DDS topics):
// checked when the configuration is read, not when DDS starts, so that a bad
// name is a configuration error (exit 3), not a restart loop.
#include <cstddef>
#include <string>
#include <string_view>

namespace ceilpose {

// One length for robot names everywhere: the DDS topics, the keystore's
// certificate subject (CN, at most 64 characters) and the fleet segment's
// name field (64 bytes with its NUL).
inline constexpr size_t kMaxRobotNameLength = 63;

// A legal single-token ROS 2 name (rmw_validate_namespace's rules for one
// token): [A-Za-z_][A-Za-z0-9_]*, without repeated underscores, of at most
// kMaxRobotNameLength characters.
bool is_valid_ros_name(std::string_view name);

// The rule above in words, for every message that refuses a robot name.
inline constexpr const char* kRosNameRule =
    "a ROS 2 name token of at most 63 characters: a letter or '_', then letters, digits and "
    "single '_' (no '-' or '.')";

// Replaces every character a ROS name token may not hold ('-', '.', ...) with
// '_' (collapsing runs), prefixes 'r' to a leading digit and cuts it to
// kMaxRobotNameLength: host names such as "robot-7" then become usable robot
// names ("robot_7"). Empty input yields empty output.
std::string to_ros_name(std::string_view text);

}  // namespace ceilpose
