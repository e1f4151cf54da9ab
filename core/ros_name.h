#pragma once
// The robot name is a ROS 2 name token (the namespace of its DDS topics):
// checked when the configuration is read, not when DDS starts, so that a bad
// name is a configuration error (exit 3), not a restart loop.
#include <string>
#include <string_view>

namespace ceilpose {

// A legal single-token ROS 2 name (rmw_validate_namespace's rules for one
// token): [A-Za-z_][A-Za-z0-9_]*, without repeated underscores.
bool is_valid_ros_name(std::string_view name);

// Replaces every character a ROS name token may not hold ('-', '.', ...) with
// '_' (collapsing runs) and prefixes 'r' to a leading digit: host names such as "robot-7" then
// become usable robot names ("robot_7"). Empty input yields empty output.
std::string to_ros_name(std::string_view text);

}  // namespace ceilpose
