// Strict YAML reading: every key is checked against the schema in
// config_schema.h, and the first problem ends the load with a message that
// names the origin, the line, the key path, what was expected and what was
// found. Runs at start-up and on SIGHUP only, so exceptions are used inside
// and turned into a Result at the boundary.
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "capture/source_spec.h"
#include "capture/synthetic_source.h"
#include "config/config_schema.h"
#include "core/text_file.h"
#include "core/yaml_duplicate_keys.h"

namespace ceilpose {
namespace {

using config_detail::Choices;
using config_detail::TextCheck;

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string describe_found(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "nothing (null)";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a mapping";
    case YAML::NodeType::Scalar:
      return "'" + node.Scalar() + "'";
    default:
      return "an undefined node";
  }
}

template <typename T>
std::string number_text(T value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

class Reader {
 public:
  Reader(const YAML::Node& root, std::string origin, std::vector<std::string>* missing)
      : origin_(std::move(origin)), missing_(missing) {
    if (!root.IsNull() && !root.IsMap())
      fail(root, "", "a mapping of sections", describe_found(root));
    frames_.push_back(Frame{root, "", {}});
  }

  template <typename Fn>
  void section(const char* name, Fn fn) {
    YAML::Node node = child(name);
    if (node.IsDefined() && !node.IsNull() && !node.IsMap())
      fail(node, path(name), "a mapping", describe_found(node));
    frames_.push_back(Frame{node, path(name), {}});
    fn();
    check_unknown_keys(frames_.back());
    frames_.pop_back();
  }

  template <typename T>
  void field(const char* name, T& value, T min, T max) {
    YAML::Node node = child(name);
    if (!present(node, name)) return;
    T parsed{};
    const std::string& s = node.IsScalar() ? node.Scalar() : std::string();
    if (!node.IsScalar() || !parse_number(s, &parsed))
      fail(node, path(name), std::is_integral_v<T> ? "an integer" : "a number",
           describe_found(node));
    if (parsed < min || parsed > max)
      fail(node, path(name), "a value in [" + number_text(min) + ", " + number_text(max) + "]",
           "'" + s + "'");
    value = parsed;
  }

  void field(const char* name, bool& value) {
    YAML::Node node = child(name);
    if (!present(node, name)) return;
    // Only the YAML 1.2 spellings: 'yes'/'on' are too easy to write by mistake.
    if (node.IsScalar() && node.Scalar() == "true") {
      value = true;
    } else if (node.IsScalar() && node.Scalar() == "false") {
      value = false;
    } else {
      fail(node, path(name), "true or false", describe_found(node));
    }
  }

  void text(const char* name, std::string& value, TextCheck check) {
    YAML::Node node = child(name);
    if (!present(node, name)) return;
    if (!node.IsScalar()) fail(node, path(name), "a string", describe_found(node));
    if (const char* expected = check(node.Scalar()))
      fail(node, path(name), expected, describe_found(node));
    value = node.Scalar();
  }

  void texts(const char* name, std::vector<std::string>& value, TextCheck check) {
    YAML::Node node = child(name);
    if (!present(node, name)) return;
    if (!node.IsSequence()) fail(node, path(name), "a list of strings", describe_found(node));
    std::vector<std::string> parsed;
    for (size_t i = 0; i < node.size(); ++i) {
      const YAML::Node item = std::as_const(node)[i];
      const std::string item_path = path(name) + "[" + std::to_string(i) + "]";
      if (!item.IsScalar()) fail(item, item_path, "a string", describe_found(item));
      if (const char* expected = check(item.Scalar()))
        fail(item, item_path, expected, describe_found(item));
      parsed.push_back(item.Scalar());
    }
    value = std::move(parsed);
  }

  template <typename T>
  void choice(const char* name, T& value, Choices<T> choices) {
    YAML::Node node = child(name);
    if (!present(node, name)) return;
    std::string expected = "one of";
    for (const auto& [text, v] : choices) {
      if (node.IsScalar() && node.Scalar() == text) {
        value = v;
        return;
      }
      expected += std::string(" ") + text;
    }
    fail(node, path(name), expected, describe_found(node));
  }

  template <size_t N>
  void numbers(const char* name, std::array<double, N>& value) {
    YAML::Node node = child(name);
    if (!present(node, name)) return;
    const std::string expected = "a list of " + std::to_string(N) + " numbers";
    if (!node.IsSequence() || node.size() != N)
      fail(node, path(name), expected, describe_found(node));
    std::array<double, N> parsed{};
    for (size_t i = 0; i < N; ++i) {
      const YAML::Node item = std::as_const(node)[i];
      if (!item.IsScalar() || !parse_number(item.Scalar(), &parsed[i]))
        fail(item, path(name) + "[" + std::to_string(i) + "]", "a number", describe_found(item));
    }
    value = parsed;
  }

  void colour(const char* name, Rgb& value) {
    YAML::Node node = child(name);
    if (!present(node, name)) return;
    const char* kExpected = "an sRGB colour [r, g, b], each 0..255";
    if (!node.IsSequence() || node.size() != 3)
      fail(node, path(name), kExpected, describe_found(node));
    std::array<uint8_t, 3> parsed{};
    for (size_t i = 0; i < 3; ++i) {
      const YAML::Node item = std::as_const(node)[i];
      int channel = -1;
      if (!item.IsScalar() || !parse_number(item.Scalar(), &channel) || channel < 0 ||
          channel > 255)
        fail(item, path(name) + "[" + std::to_string(i) + "]", kExpected, describe_found(item));
      parsed[i] = static_cast<uint8_t>(channel);
    }
    value = Rgb{parsed[0], parsed[1], parsed[2]};
  }

  // Top-level keys are checked once every section has been visited.
  void finish() { check_unknown_keys(frames_.front()); }

  // Cross-key rules, reported at the line of the key that has to change.
  void require(bool ok, const std::string& key_path, const std::string& message) {
    if (ok) return;
    // yaml-cpp's Node::operator= rebinds the tree, so walk with fresh copies.
    std::vector<YAML::Node> walk{frames_.front().node};
    std::stringstream parts(key_path);
    for (std::string part; std::getline(parts, part, '.');) {
      const YAML::Node& parent = walk.back();
      if (!parent.IsMap() || !parent[part]) break;
      walk.push_back(parent[part]);
    }
    throw ConfigError(where(walk.back()) + key_path + ": " + message);
  }

 private:
  struct Frame {
    YAML::Node node;
    std::string path;
    std::set<std::string> known;
  };

  YAML::Node child(const char* name) {
    Frame& f = frames_.back();
    f.known.insert(name);
    if (!f.node.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
    const YAML::Node& parent = f.node;
    // A missing key yields an invalid node that throws on any query.
    YAML::Node node = parent[name];
    if (!node.IsDefined()) return YAML::Node(YAML::NodeType::Undefined);
    return node;
  }

  bool present(const YAML::Node& node, const char* name) {
    if (node.IsDefined()) return true;
    if (missing_ != nullptr) missing_->push_back(path(name));
    return false;
  }

  std::string path(const char* name) const {
    const std::string& base = frames_.back().path;
    return base.empty() ? std::string(name) : base + "." + name;
  }

  template <typename T>
  static bool parse_number(const std::string& s, T* out) {
    const char* end = s.data() + s.size();
    auto [ptr, ec] = std::from_chars(s.data(), end, *out);
    if (ec != std::errc() || ptr != end) return false;
    if constexpr (std::is_floating_point_v<T>) return std::isfinite(*out);
    return true;
  }

  void check_unknown_keys(const Frame& f) {
    if (!f.node.IsMap()) return;
    std::set<std::string> seen;
    for (auto it = f.node.begin(); it != f.node.end(); ++it) {
      const std::string key = it->first.Scalar();
      const std::string key_path = f.path.empty() ? key : f.path + "." + key;
      if (!seen.insert(key).second)
        throw ConfigError(where(it->first) + key_path + ": key appears twice");
      if (f.known.count(key) == 0) {
        std::string known;
        for (const auto& k : f.known) known += (known.empty() ? "" : ", ") + k;
        throw ConfigError(where(it->first) + "unknown key '" + key_path + "'" +
                          (f.path.empty() ? "" : " in section '" + f.path + "'") +
                          " (known keys: " + known + ")");
      }
    }
  }

  std::string where(const YAML::Node& node) const {
    const YAML::Mark mark = node.Mark();
    if (mark.line < 0) return origin_ + ": ";
    return origin_ + ":" + std::to_string(mark.line + 1) + ": ";
  }

  [[noreturn]] void fail(const YAML::Node& node, const std::string& key_path,
                         const std::string& expected, const std::string& found) const {
    throw ConfigError(where(node) + (key_path.empty() ? "" : key_path + ": ") + "expected " +
                      expected + ", found " + found);
  }

  std::string origin_;
  std::vector<std::string>* missing_;
  std::vector<Frame> frames_;
};

void check_cross_keys(Reader& r, const ServiceConfig& c) {
  const PipelineConfig& p = c.pipeline;
  r.require(p.layout.height_m > p.mount.lens_height_m, "ceiling.height_m",
            "expected a ceiling above the lens (mount.lens_height_m = " +
                number_text(p.mount.lens_height_m) + "), found " + number_text(p.layout.height_m));
  const capture::SourceOptions& s = c.capture.device;
  r.require(
      s.reconnect_max_ms >= s.reconnect_initial_ms, "capture.reconnect_max_ms",
      "expected at least capture.reconnect_initial_ms = " + std::to_string(s.reconnect_initial_ms) +
          ", found " + std::to_string(s.reconnect_max_ms));
  r.require(!capture::is_synthetic_spec(c.capture.source) ||
                capture::synthetic_pixel_format(s.pixel_formats).has_value(),
            "capture.pixel_format",
            "expected auto (RGB24) or a format the synthetic camera hands over (yuyv, nv12, "
            "yuv420, rgb24, bgr24, gray8), found mjpeg");
  r.require(c.fleet.remove_after_ms >= c.fleet.stale_after_ms, "fleet.remove_after_ms",
            "expected at least fleet.stale_after_ms = " + std::to_string(c.fleet.stale_after_ms) +
                " (a robot turns stale before it is removed), found " +
                std::to_string(c.fleet.remove_after_ms));
  const int capture_priority = c.capture.thread.realtime_priority;
  r.require(c.capture.pipeline_rt_priority == 0 || capture_priority == 0 ||
                c.capture.pipeline_rt_priority < capture_priority,
            "capture.pipeline_rt_priority",
            "expected a priority below capture.rt_priority = " + std::to_string(capture_priority) +
                " (the capture thread must preempt it), found " +
                std::to_string(c.capture.pipeline_rt_priority));
  const CameraIntrinsics& k = p.intrinsics;
  r.require(static_cast<long>(k.width) * k.height <= kMaxImagePixels, "camera.height",
            "expected at most " + std::to_string(kMaxImagePixels) + " pixels (camera.width x " +
                "camera.height), found " + std::to_string(k.width) + "x" +
                std::to_string(k.height));
  const std::string lens = distortion_problem(k);
  r.require(lens.empty(), "camera.distortion", "expected a lens this camera can have: " + lens);
  // Each window must be a window: a minimum above its maximum accepts no
  // rectangle, and the daemon would never have a fix.
  const DetectorParams& d = p.detector;
  auto window = [&](double lo, double hi, const char* lo_key, const char* hi_key) {
    r.require(lo <= hi, std::string("detector.") + lo_key,
              std::string("expected at most detector.") + hi_key + " = " + number_text(hi) +
                  ", found " + number_text(lo));
  };
  window(d.aspect_min, d.aspect_max, "aspect_min", "aspect_max");
  window(d.fill_min, d.fill_max, "fill_min", "fill_max");
  window(d.area_min_ratio, d.area_max_ratio, "area_min_ratio", "area_max_ratio");
  // A marker (red and green side by side, East) must fit its grid cell.
  r.require(
      2.0 * p.layout.rect_width_m < p.layout.grid_m && p.layout.rect_height_m < p.layout.grid_m,
      "ceiling.rect_width_m",
      "expected a marker (2 x ceiling.rect_width_m wide, ceiling.rect_height_m tall) "
      "inside its grid cell (ceiling.grid_m = " +
          number_text(p.layout.grid_m) + "), found " + number_text(p.layout.rect_width_m) + " x " +
          number_text(p.layout.rect_height_m) + " m rectangles");
  const double marker_n_m = (p.layout.bits - 1) * p.layout.slot_pitch_m;
  r.require(marker_n_m < p.layout.rect_height_m, "ceiling.slot_pitch_m",
            "expected all " + std::to_string(p.layout.bits) +
                " bit slots inside the rectangle (ceiling.rect_height_m = " +
                number_text(p.layout.rect_height_m) + "), found a pitch of " +
                number_text(p.layout.slot_pitch_m));
}

Result<ServiceConfig> read_tree(const YAML::Node& root, const ServiceConfig& base,
                                const std::string& origin, std::vector<std::string>* missing) {
  try {
    ServiceConfig config = base;
    Reader reader(root, origin, missing);
    config_detail::describe(reader, config);
    reader.finish();
    check_cross_keys(reader, config);
    return config;
  } catch (const ConfigError& e) {
    return make_error(e.what());
  } catch (const YAML::Exception& e) {
    return make_error(origin + ": " + e.what());
  }
}

Result<ServiceConfig> parse(const std::string& text, const std::string& origin,
                            std::vector<std::string>* missing) {
  // ceilpose.yaml, every key written out, has about 250 entries.
  constexpr size_t kMaxConfigNodes = 10000;
  if (auto plain = check_plain_yaml(text, origin, kMaxConfigNodes); !plain) return plain.error();
  YAML::Node root;
  try {
    root.reset(YAML::Load(text));
  } catch (const YAML::ParserException& e) {
    return make_error(origin + ":" + std::to_string(e.mark.line + 1) + ":" +
                      std::to_string(e.mark.column + 1) + ": YAML syntax error: " + e.msg);
  }
  return read_tree(root, default_config(), origin, missing);
}

}  // namespace

ServiceConfig default_config() { return ServiceConfig{}; }

Result<ServiceConfig> load_config_string(const std::string& yaml_text, const std::string& origin) {
  return parse(yaml_text, origin, nullptr);
}

Result<ServiceConfig> load_config_file(const std::string& path) {
  auto text = read_text_file(path, "configuration file");
  if (!text) return text.error();
  auto config = parse(*text, path, nullptr);
  if (!config) return config;
  // A relative camera.calibration_file or ceiling.map names a file beside
  // the configuration, wherever the command runs (issue 28: they resolved
  // against the current directory, so --check-config answered by cwd).
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  for (std::string* file : {&config->calibration.camera_file, &config->calibration.map_file})
    if (!file->empty() && std::filesystem::path(*file).is_relative() && !dir.empty())
      *file = (dir / *file).lexically_normal().string();
  return config;
}

Result<ServiceConfig> with_calibration_files(ServiceConfig config) {
  const CameraIntrinsics& k = config.pipeline.intrinsics;
  const std::string capture =
      "the capture (camera.width x camera.height = " + std::to_string(k.width) + "x" +
      std::to_string(k.height) + ")";
  auto loaded = load_calibration_files(config.calibration, capture, &config.pipeline);
  if (!loaded) return loaded.error();
  return config;
}

Result<ServiceConfig> apply_overrides(const ServiceConfig& base,
                                      const std::vector<ConfigOverride>& overrides) {
  ServiceConfig config = base;
  for (const ConfigOverride& o : overrides) {
    // The same reader as for files, on a one-key tree built from the path.
    YAML::Node root(YAML::NodeType::Map);
    std::stringstream parts(o.key_path);
    std::vector<std::string> keys;
    for (std::string part; std::getline(parts, part, '.');) keys.push_back(part);
    if (keys.empty()) return make_error(o.origin + ": empty configuration key");
    std::vector<YAML::Node> chain{root};
    for (size_t i = 0; i + 1 < keys.size(); ++i) {
      YAML::Node child(YAML::NodeType::Map);
      chain.back()[keys[i]] = child;
      chain.push_back(child);
    }
    chain.back()[keys.back()] = o.value;
    auto next = read_tree(root, config, o.origin, nullptr);
    if (!next) return next.error();
    config = std::move(next).value();
  }
  return config;
}

Result<std::vector<std::string>> missing_config_keys(const std::string& yaml_text,
                                                     const std::string& origin) {
  std::vector<std::string> missing;
  auto parsed = parse(yaml_text, origin, &missing);
  if (!parsed) return parsed.error();
  return missing;
}

std::string_view to_string(LogLevel level) {
  switch (level) {
    case LogLevel::kTrace:
      return "trace";
    case LogLevel::kDebug:
      return "debug";
    case LogLevel::kInfo:
      return "info";
    case LogLevel::kWarn:
      return "warn";
    case LogLevel::kError:
      return "error";
    case LogLevel::kCritical:
      return "critical";
    case LogLevel::kOff:
      return "off";
  }
  return "unknown";
}

}  // namespace ceilpose
