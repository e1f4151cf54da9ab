#include "calibration/map_file.h"

#include <cmath>
#include <cstdio>

#include "calibration/yaml_fields.h"
#include "core/text_file.h"

namespace ceilpose {
namespace {

using namespace calibration_detail;

// SPEC §8's keys of a marker entry: read, checked and written from here.
namespace key {
constexpr const char* kCode = "code";
constexpr const char* kX = "x_m";
constexpr const char* kY = "y_m";
constexpr const char* kYaw = "yaw_rad";
constexpr const char* kSigma = "sigma_m";
constexpr const char* kSigmaYaw = "sigma_yaw_rad";
constexpr const char* kObservations = "observations";
}  // namespace key

// Sigmas beyond these describe no marker (issue 28: 1e154 gave NaN
// covariances downstream): a map entry is known to a grid unit or better.
constexpr double kMaxMapSigmaM = 1.0;
constexpr double kMaxMapSigmaRad = 3.141592653589793;
// SPEC §8's datum, as read: the best rigid fit of the centres onto the
// nominal grid may differ from the identity by rounding and hand edits,
// not by a moved or turned map.
constexpr double kDatumShiftM = 0.005;
constexpr double kDatumTurnRad = 0.1 * 3.141592653589793 / 180.0;

std::string shown_number(double v) {
  char t[32];
  std::snprintf(t, sizeof t, "%.6g", v);
  return t;
}

// The map's ceiling must be the configured one: a map surveyed under another
// height or grid would place every marker wrongly without any error.
Result<void> check_ceiling(const std::string& path, const YAML::Node& root,
                           const CeilingLayout& layout) {
  const YAML::Node ceiling = root["ceiling"];
  if (!ceiling.IsDefined() || ceiling.IsNull()) return {};  // optional: the configured one
  if (!ceiling.IsMap())
    return make_error(where(path, ceiling) + ": key 'ceiling' must be a mapping");
  if (auto known = only_keys(path, ceiling, {"height_m", "grid_m", "bits"}, "ceiling"); !known)
    return known;
  for (auto [key, configured] :
       {std::pair{"height_m", layout.height_m}, std::pair{"grid_m", layout.grid_m}}) {
    auto v = finite_number(path, ceiling, key, std::string("ceiling.") + key, &configured);
    if (!v) return v.error();
    if (std::abs(*v - configured) > 1e-6 * std::max(1.0, std::abs(configured))) {
      char msg[200];
      std::snprintf(msg, sizeof msg,
                    ": ceiling.%s is %.6f m but the configuration's ceiling.%s is %.6f m (survey "
                    "again or configure the ceiling the map was made for)",
                    key, *v, key, configured);
      return make_error(where(path, ceiling[key]) + msg);
    }
  }
  auto bits = integer(path, ceiling, "bits", "ceiling.bits", &layout.bits);
  if (!bits) return bits.error();
  if (*bits != layout.bits) {
    return make_error(where(path, ceiling["bits"]) + ": ceiling.bits is " + std::to_string(*bits) +
                      " but the configuration's ceiling.bits is " + std::to_string(layout.bits));
  }
  return {};
}

Result<void> read_marker(const std::string& path, const YAML::Node& node, size_t index,
                         CeilingMap* map) {
  const std::string name = "markers[" + std::to_string(index) + "]";
  if (!node.IsMap()) return make_error(where(path, node) + ": " + name + " must be a mapping");
  if (auto known = only_keys(path, node,
                             {key::kCode, key::kX, key::kY, key::kYaw, key::kSigma, key::kSigmaYaw,
                              key::kObservations},
                             name);
      !known) {
    return known;
  }
  const YAML::Node code = node[key::kCode];
  int ij[2] = {0, 0};
  // A missing key is an invalid node, whose type yaml-cpp throws for
  // (found by fuzz_map).
  bool code_ok = code.IsDefined() && code.IsSequence() && code.size() == 2;
  for (int k = 0; code_ok && k < 2; ++k)
    code_ok = code[k].IsScalar() && YAML::convert<int>::decode(code[k], ij[k]);
  if (!code_ok) {
    return make_error(where(path, code.IsDefined() ? code : node) + ": " + name +
                      ".code must be a pair of integers [i, j]");
  }
  const std::string entry =
      name + " (code [" + std::to_string(ij[0]) + ", " + std::to_string(ij[1]) + "])";
  if (!map->valid_code(ij[0], ij[1])) {
    return make_error(where(path, code) + ": " + entry + ": code outside the ceiling's " +
                      std::to_string(map->codes()) + " x " + std::to_string(map->codes()) +
                      " codes (ceiling.bits)");
  }
  if (map->find(ij[0], ij[1]) != nullptr)
    return make_error(where(path, code) + ": " + entry + ": code listed twice");
  MarkerPlacement p;
  p.present = true;
  const double zero = 0.0;
  struct Field {
    const char* key;
    double* dst;
    const double* fallback;
    bool non_negative;
    const double* limit;
  };
  for (const Field& f : {Field{key::kX, &p.x_m, nullptr, false, nullptr},
                         Field{key::kY, &p.y_m, nullptr, false, nullptr},
                         Field{key::kYaw, &p.yaw_rad, &zero, false, nullptr},
                         Field{key::kSigma, &p.sigma_m, &zero, true, &kMaxMapSigmaM},
                         Field{key::kSigmaYaw, &p.sigma_yaw_rad, &zero, true, &kMaxMapSigmaRad}}) {
    auto v = finite_number(path, node, f.key, entry + "." + f.key, f.fallback);
    if (!v) return v.error();
    if (f.non_negative && *v < 0.0)
      return make_error(where(path, node[f.key]) + ": " + entry + "." + f.key + " is negative");
    if (f.limit != nullptr && *v > *f.limit)
      return make_error(where(path, node[f.key]) + ": " + entry + "." + f.key + " is " +
                        shown_number(*v) + ", over " + shown_number(*f.limit) +
                        ": a marker known no better than that is not mapped");
    *f.dst = *v;
  }
  const int none = 0;
  auto obs = integer(path, node, key::kObservations, entry + "." + key::kObservations, &none);
  if (!obs) return obs.error();
  if (*obs < 0)
    return make_error(where(path, node[key::kObservations]) + ": " + entry + "." +
                      key::kObservations + " is negative");
  p.observations = *obs;
  map->set(ij[0], ij[1], p);
  return {};
}

}  // namespace

static Result<CeilingMap> read_map(const std::string& path, const CeilingLayout& layout);

Result<CeilingMap> read_map_file(const std::string& path, const CeilingLayout& layout) {
  // What yaml-cpp may still throw on a node shape the checks above did not
  // foresee is an error in the file, not a crash.
  try {
    return read_map(path, layout);
  } catch (const YAML::Exception& e) {
    return make_error(path + ": malformed ceiling map (" + e.what() + ")");
  }
}

static Result<CeilingMap> read_map(const std::string& path, const CeilingLayout& layout) {
  // A marker is 17 entries (its mapping, six keys with values, the code's
  // list of two); a map holds each code once.
  const size_t codes = static_cast<size_t>(layout.codes());
  auto root = load_yaml_mapping(path, "ceiling map", 20 * codes * codes + 64);
  if (!root) return root.error();
  if (auto known = only_keys(path, *root, {"format", "version", "ceiling", "markers"}, "");
      !known) {
    return known.error();
  }
  auto format = text(path, *root, "format", "format");
  if (!format) return format.error();
  if (*format != kMapFormat) {
    return make_error(where(path, (*root)["format"]) + ": format '" + *format + "' is not '" +
                      kMapFormat + "'");
  }
  auto version = integer(path, *root, "version", "version");
  if (!version) return version.error();
  if (*version != kMapVersion) {
    return make_error(where(path, (*root)["version"]) + ": unsupported version " +
                      std::to_string(*version) + " (this reader knows version " +
                      std::to_string(kMapVersion) + ")");
  }
  if (auto ceiling = check_ceiling(path, *root, layout); !ceiling) return ceiling.error();
  const YAML::Node markers = (*root)["markers"];
  if (!markers.IsDefined() || !markers.IsSequence() || markers.size() == 0) {
    return make_error((markers.IsDefined() ? where(path, markers) : path + ":1") +
                      ": key 'markers' must be a non-empty list of markers");
  }
  CeilingMap map = CeilingMap::empty(layout);
  for (size_t k = 0; k < markers.size(); ++k) {
    if (auto read = read_marker(path, markers[k], k, &map); !read) return read.error();
  }
  const PlaneMotion datum = datum_motion(map, layout);
  if (std::hypot(datum.tx_m, datum.ty_m) > kDatumShiftM ||
      std::abs(datum.rotation_rad) > kDatumTurnRad) {
    char msg[320];
    std::snprintf(msg, sizeof msg,
                  ": the map breaks SPEC §8's datum: the best rigid fit of its %d centres onto "
                  "the nominal grid moves them by (%.1f, %.1f) mm and turns them by %.3f deg "
                  "(limits %.0f mm, %.1f deg); a survey writes maps in the datum, a map moved or "
                  "turned by hand must be moved back",
                  map.present_count(), 1000.0 * datum.tx_m, 1000.0 * datum.ty_m,
                  datum.rotation_rad * 180.0 / 3.141592653589793, 1000.0 * kDatumShiftM,
                  kDatumTurnRad * 180.0 / 3.141592653589793);
    return make_error(path + msg);
  }
  return map;
}

std::string map_text(const CeilingMap& map, const CeilingLayout& layout) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line,
                "format: %s\nversion: %d\nceiling:\n  height_m: %.6f\n  grid_m: %.6f\n  bits: "
                "%d\nmarkers:\n",
                kMapFormat, kMapVersion, layout.height_m, layout.grid_m, layout.bits);
  out += line;
  for (int j = 0; j < map.codes(); ++j)
    for (int i = 0; i < map.codes(); ++i) {
      const MarkerPlacement* p = map.find(i, j);
      if (p == nullptr) continue;
      std::snprintf(line, sizeof line,
                    "  - %s: [%d, %d]\n    %s: %.6f\n    %s: %.6f\n    %s: %.7f\n    %s: %.7f\n"
                    "    %s: %.7f\n    %s: %d\n",
                    key::kCode, i, j, key::kX, p->x_m, key::kY, p->y_m, key::kYaw, p->yaw_rad,
                    key::kSigma, p->sigma_m, key::kSigmaYaw, p->sigma_yaw_rad, key::kObservations,
                    p->observations);
      out += line;
    }
  return out;
}

Result<void> write_map_file(const std::string& path, const CeilingMap& map,
                            const CeilingLayout& layout) {
  return replace_file(path, map_text(map, layout));
}

}  // namespace ceilpose
