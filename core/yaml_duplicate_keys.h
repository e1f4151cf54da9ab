#pragma once
// yaml-cpp keeps both entries of a key written twice and a lookup answers the
// first: a file a person edited could then mean something else than what it
// shows. Readers of such files (recording.yaml, calibration, the ceiling
// map) refuse it with this. Header-only: core itself does not link yaml-cpp.
#include <yaml-cpp/yaml.h>

#include <set>
#include <string>

#include "core/result.h"

namespace ceilpose {

// The first key that appears twice in one mapping anywhere in `node`, as
// "PATH:LINE: key 'a.b' appears twice"; success when there is none.
inline Result<void> check_no_duplicate_keys(const YAML::Node& node, const std::string& path,
                                            const std::string& key_path = "") {
  if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i) {
      auto ok = check_no_duplicate_keys(node[i], path, key_path + "[" + std::to_string(i) + "]");
      if (!ok) return ok;
    }
  }
  if (!node.IsMap()) return {};
  std::set<std::string> seen;
  for (const auto& entry : node) {
    const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : std::string("?");
    const std::string full = key_path.empty() ? key : key_path + "." + key;
    if (!seen.insert(key).second) {
      return make_error(path + ":" + std::to_string(entry.first.Mark().line + 1) + ": key '" +
                        full + "' appears twice");
    }
    if (auto ok = check_no_duplicate_keys(entry.second, path, full); !ok) return ok;
  }
  return {};
}

}  // namespace ceilpose
