#include "calibration/yaml_fields.h"

#include <cmath>
#include <cstring>
#include <type_traits>

#include "core/text_file.h"
#include "core/yaml_duplicate_keys.h"

namespace ceilpose::calibration_detail {

std::string where(const std::string& path, const YAML::Node& node) {
  return path + ":" + std::to_string(node.Mark().line + 1);
}

Result<YAML::Node> load_yaml_mapping(const std::string& path, const char* what, size_t max_nodes) {
  auto text = read_text_file(path, what, size_t{64} << 20);
  if (!text) return text.error();
  if (auto plain = check_plain_yaml(*text, path, max_nodes); !plain) return plain.error();
  YAML::Node root;
  try {
    root = YAML::Load(*text);
  } catch (const YAML::ParserException& e) {
    return make_error(path + ":" + std::to_string(e.mark.line + 1) + ":" +
                      std::to_string(e.mark.column + 1) + ": YAML syntax error: " + e.msg);
  } catch (const YAML::Exception& e) {
    return make_error(path + ": YAML error: " + e.what());
  }
  if (!root.IsMap()) return make_error(path + ":1: expected a YAML mapping (a " + what + ")");
  if (auto unique = check_no_duplicate_keys(root, path); !unique) return unique.error();
  return root;
}

namespace {

template <typename T>
Result<T> scalar(const std::string& path, const YAML::Node& parent, const char* key,
                 const std::string& key_path, const T* fallback, const char* expected) {
  const YAML::Node node = parent[key];
  if (!node.IsDefined() || node.IsNull()) {
    if (fallback != nullptr) return *fallback;
    return make_error(where(path, parent) + ": missing key '" + key_path + "'");
  }
  T value{};
  // A quoted scalar ("640") is text, however it reads: a number the file
  // wrote as a string is a mistake to name, not a value to guess.
  const bool quoted_number = std::is_arithmetic_v<T> && node.IsScalar() && node.Tag() == "!";
  if (!node.IsScalar() || quoted_number || !YAML::convert<T>::decode(node, value)) {
    return make_error(where(path, node) + ": key '" + key_path + "' must be " + expected +
                      (node.IsScalar()
                           ? std::string(quoted_number ? ", found the string '" : ", found '") +
                                 node.Scalar() + "'"
                           : std::string()));
  }
  return value;
}

}  // namespace

Result<double> finite_number(const std::string& path, const YAML::Node& parent, const char* key,
                             const std::string& key_path, const double* fallback) {
  auto v = scalar<double>(path, parent, key, key_path, fallback, "a finite number");
  if (v && !std::isfinite(*v)) {
    return make_error(where(path, parent[key]) + ": key '" + key_path +
                      "' must be a finite number, found '" + parent[key].Scalar() + "'");
  }
  return v;
}

Result<int> integer(const std::string& path, const YAML::Node& parent, const char* key,
                    const std::string& key_path, const int* fallback) {
  return scalar<int>(path, parent, key, key_path, fallback, "an integer");
}

Result<std::string> text(const std::string& path, const YAML::Node& parent, const char* key,
                         const std::string& key_path) {
  return scalar<std::string>(path, parent, key, key_path, nullptr, "a string");
}

Result<void> only_keys(const std::string& path, const YAML::Node& node,
                       std::initializer_list<const char*> known, const std::string& key_path) {
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>("");
    bool ok = false;
    for (const char* k : known) ok = ok || key == k;
    if (ok) continue;
    std::string list;
    for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
    return make_error(where(path, kv.first) + ": unknown key '" +
                      (key_path.empty() ? key : key_path + "." + key) + "' (expected " + list +
                      ")");
  }
  return {};
}

}  // namespace ceilpose::calibration_detail
