#include "core/ros_name.h"

#include <cctype>

namespace ceilpose {
namespace {

bool is_alpha(char c) { return std::isalpha(static_cast<unsigned char>(c)) != 0; }
bool is_alnum(char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0; }

}  // namespace

bool is_valid_ros_name(std::string_view name) {
  if (name.empty() || name.size() > kMaxRobotNameLength || !(is_alpha(name[0]) || name[0] == '_'))
    return false;
  for (size_t k = 0; k < name.size(); ++k) {
    const char c = name[k];
    if (!(is_alnum(c) || c == '_')) return false;
    if (c == '_' && k + 1 < name.size() && name[k + 1] == '_') return false;
  }
  return true;
}

std::string to_ros_name(std::string_view text) {
  std::string out;
  for (char c : text) {
    const char mapped = is_alnum(c) ? c : '_';
    if (mapped == '_' && !out.empty() && out.back() == '_') continue;
    out.push_back(mapped);
  }
  if (!out.empty() && std::isdigit(static_cast<unsigned char>(out[0])) != 0) {
    out.insert(out.begin(), 'r');
  }
  if (out.size() > kMaxRobotNameLength) out.resize(kMaxRobotNameLength);
  return out;
}

}  // namespace ceilpose
