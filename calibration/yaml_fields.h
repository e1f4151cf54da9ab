#pragma once
// Strict reading of the small YAML files a lab writes or a tool writes for
// it (ceiling map, camera calibration). Every error names the file, the line
// and the key. Internal to calibration/.
#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <string>

#include "core/result.h"

namespace ceilpose::calibration_detail {

// The file's root mapping; a missing file, a directory, bad syntax, more
// than `max_nodes` YAML entries (check_plain_yaml) or a root that is not a
// mapping is an error.
Result<YAML::Node> load_yaml_mapping(const std::string& path, const char* what, size_t max_nodes);

// "FILE:LINE" of a node.
std::string where(const std::string& path, const YAML::Node& node);

// `parent[key]` as a finite number. Absent: `fallback` when given, else an
// error. `key_path` is how the message names the key ("markers[3].x_m").
Result<double> finite_number(const std::string& path, const YAML::Node& parent, const char* key,
                             const std::string& key_path, const double* fallback = nullptr);
Result<int> integer(const std::string& path, const YAML::Node& parent, const char* key,
                    const std::string& key_path, const int* fallback = nullptr);
Result<std::string> text(const std::string& path, const YAML::Node& parent, const char* key,
                         const std::string& key_path);

// Error for the first key of `node` not in `known`.
Result<void> only_keys(const std::string& path, const YAML::Node& node,
                       std::initializer_list<const char*> known, const std::string& key_path);

}  // namespace ceilpose::calibration_detail
