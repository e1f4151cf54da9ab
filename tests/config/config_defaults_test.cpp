// The shipped config/ceilpose.yaml, the built-in defaults and SPEC.md agree,
// and every field of the pipeline's parameter structs has a key.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "config/config_schema.h"
#include "config/service_config.h"

namespace ceilpose {
namespace {

const std::string kShipped = std::string(CEILPOSE_SOURCE_DIR) + "/config/ceilpose.yaml";

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Number of members of an aggregate, by trying ever longer brace lists.
struct AnyMember {
  template <typename T>
  operator T() const;  // NOLINT: only used in unevaluated context
};
template <typename T, typename... A>
constexpr size_t member_count() {
  if constexpr (requires { T{A{}..., AnyMember{}}; }) {
    return member_count<T, A..., AnyMember>();
  } else {
    return sizeof...(A);
  }
}

size_t keys_in_section(const std::string& section) {
  size_t n = 0;
  for (const auto& k : config_key_paths()) n += k.rfind(section + ".", 0) == 0 ? 1 : 0;
  return n;
}

bool same_scalar(const std::string& a, const std::string& b) {
  double x = 0, y = 0;
  const auto ra = std::from_chars(a.data(), a.data() + a.size(), x);
  const auto rb = std::from_chars(b.data(), b.data() + b.size(), y);
  const bool ax = ra.ec == std::errc() && ra.ptr == a.data() + a.size();
  const bool by = rb.ec == std::errc() && rb.ptr == b.data() + b.size();
  if (ax && by) return std::abs(x - y) <= 1e-12 * std::max(1.0, std::abs(x));
  return a == b;
}

// Compares two YAML trees; numbers within rounding of their printed form.
void expect_same_tree(const YAML::Node& a, const YAML::Node& b, const std::string& path) {
  ASSERT_EQ(a.Type(), b.Type()) << path;
  if (a.IsScalar()) {
    EXPECT_TRUE(same_scalar(a.Scalar(), b.Scalar()))
        << path << ": " << a.Scalar() << " vs " << b.Scalar();
  } else if (a.IsSequence()) {
    ASSERT_EQ(a.size(), b.size()) << path;
    for (size_t i = 0; i < a.size(); ++i)
      expect_same_tree(a[i], b[i], path + "[" + std::to_string(i) + "]");
  } else if (a.IsMap()) {
    ASSERT_EQ(a.size(), b.size()) << path;
    for (auto it = a.begin(); it != a.end(); ++it) {
      const std::string key = it->first.Scalar();
      ASSERT_TRUE(b[key]) << path << "." << key << " missing";
      expect_same_tree(it->second, b[key], path + "." + key);
    }
  }
}

TEST(ConfigDefaults, MatchSpec) {
  const ServiceConfig c = default_config();
  EXPECT_EQ(c.pipeline.intrinsics.width, 640);
  EXPECT_EQ(c.pipeline.intrinsics.height, 480);
  EXPECT_DOUBLE_EQ(c.pipeline.intrinsics.fx, 530.0);
  EXPECT_DOUBLE_EQ(c.pipeline.intrinsics.fy, 530.0);
  EXPECT_DOUBLE_EQ(c.pipeline.intrinsics.cx, 319.5);
  EXPECT_DOUBLE_EQ(c.pipeline.intrinsics.cy, 239.5);
  EXPECT_DOUBLE_EQ(c.pipeline.layout.height_m, 2.4384);
  EXPECT_DOUBLE_EQ(c.pipeline.layout.grid_m, 0.6096);
  EXPECT_EQ(c.pipeline.layout.bits, 3);
  EXPECT_DOUBLE_EQ(c.pipeline.mount.lens_height_m, 0.3048);
  EXPECT_EQ(c.capture.source, "synthetic");
  EXPECT_EQ(c.ipc.name, "/ceilpose");
  EXPECT_EQ(c.dds.publisher.domain.domain_id, 0u);
  EXPECT_EQ(c.dds.publisher.robot, "");  // host name, resolved at start-up
}

TEST(ConfigDefaults, ShippedFileLoads) {
  auto loaded = load_config_file(kShipped);
  ASSERT_TRUE(loaded) << loaded.error().message;
}

TEST(ConfigDefaults, ShippedFileEqualsBuiltInDefaults) {
  auto loaded = load_config_file(kShipped);
  ASSERT_TRUE(loaded) << loaded.error().message;
  expect_same_tree(YAML::Load(dump_config(*loaded)), YAML::Load(dump_config(default_config())), "");
}

TEST(ConfigDefaults, ShippedFileStatesEveryKey) {
  auto missing = missing_config_keys(read_text(kShipped), kShipped);
  ASSERT_TRUE(missing) << missing.error().message;
  std::string list;
  for (const auto& k : *missing) list += k + " ";
  EXPECT_TRUE(missing->empty()) << "not in config/ceilpose.yaml: " << list;
}

TEST(ConfigDefaults, ShippedFileCommentsEveryKey) {
  std::istringstream lines(read_text(kShipped));
  int number = 0;
  for (std::string line; std::getline(lines, line);) {
    ++number;
    const bool is_key = line.find(':') != std::string::npos && line.rfind("#", 0) != 0 &&
                        line.find_first_not_of(' ') != std::string::npos &&
                        line[line.find_first_not_of(' ')] != '#';
    const bool opens_section = is_key && line[0] != ' ';
    if (is_key && !opens_section) {
      EXPECT_NE(line.find('#'), std::string::npos) << "line " << number << ": " << line;
    }
  }
}

TEST(ConfigSchema, EveryDetectorParamHasAKey) {
  EXPECT_EQ(keys_in_section("detector"), member_count<DetectorParams>());
}

TEST(ConfigSchema, EveryPositioningParamHasAKey) {
  EXPECT_EQ(keys_in_section("positioning"), member_count<PositioningParams>());
}

TEST(ConfigSchema, EveryFilterParamHasAKey) {
  EXPECT_EQ(keys_in_section("filter"), member_count<FilterParams>());
}

TEST(ConfigSchema, EveryMountFieldHasAKey) {
  EXPECT_EQ(keys_in_section("mount"), member_count<CameraMount>());
}

TEST(ConfigSchema, EveryIntrinsicsFieldHasAKey) {
  // camera.calibration_file names a file that replaces them (CalibrationFiles).
  EXPECT_EQ(keys_in_section("camera"), member_count<CameraIntrinsics>() + 1);
}

TEST(ConfigSchema, EveryCeilingFieldHasAKey) {
  // ceiling.map names the surveyed map (CalibrationFiles).
  EXPECT_EQ(keys_in_section("ceiling"), member_count<CeilingLayout>() + 1);
}

// Where each key's value lives: walks the schema (config/config_schema.h) and
// records the address and size of the field it binds.
struct FieldAddresses {
  struct Field {
    std::string key;
    const char* at;
    size_t size;
  };
  std::string section_name;
  std::vector<Field> fields;

  template <typename Fn>
  void section(const char* name, Fn&& fn) {
    const std::string outer = section_name;
    section_name = outer.empty() ? std::string(name) : outer + "." + name;
    fn();
    section_name = outer;
  }
  template <typename T, typename... Rest>
  void add(const char* name, T& value) {
    fields.push_back({section_name + "." + name, reinterpret_cast<const char*>(&value), sizeof(T)});
  }
  template <typename T, typename... Rest>
  void field(const char* name, T& value, Rest&&...) {
    add(name, value);
  }
  template <typename T, typename... Rest>
  void text(const char* name, T& value, Rest&&...) {
    add(name, value);
  }
  template <typename T, typename... Rest>
  void texts(const char* name, T& value, Rest&&...) {
    add(name, value);
  }
  template <typename T, typename C>
  void choice(const char* name, T& value, C&&) {
    add(name, value);
  }
  template <typename T>
  void numbers(const char* name, T& value) {
    add(name, value);
  }
  template <typename T>
  void colour(const char* name, T& value) {
    add(name, value);
  }
};

template <typename S>
bool inside(const FieldAddresses::Field& f, const S& module_options) {
  const char* begin = reinterpret_cast<const char*>(&module_options);
  return f.at >= begin && f.at + f.size <= begin + sizeof(S);
}

TEST(ConfigSchema, EveryKeyIsBoundToTheOptionsOfTheModuleThatUsesIt) {
  // One home per setting: a key's value lives in its module's own options
  // struct, which the module reads (pipeline's PipelineConfig, capture's
  // SourceOptions and CaptureThreadOptions, ipc's ShmOptions, DdsOptions and FleetOptions). The few keys
  // ceilposed itself consumes are listed with where; a new key that is in
  // neither fails here until it is bound where it takes effect.
  ServiceConfig c = default_config();
  FieldAddresses v;
  config_detail::describe(v, c);
  const std::set<std::string> daemon_keys{
      "capture.source",                      // make_frame_source (daemon/service.cpp)
      "capture.pipeline_rt_priority",        // WorkerOptions::rt_priority
      "capture.synthetic_seed",              // the synthetic camera's sim::TrajectoryCamera
      "positioning.mode",                    // PositioningParams::mode
      "logging.level",                       // set_log_level
      "logging.problem_report_interval_ms",  // the problem line's period
      "watchdog.max_stall_ms",               // WatchdogGate
      "watchdog.status_interval_ms",         // STATUS= and ShmPoseSink's status period
      "dds.enabled",                         // whether Service::start_dds runs
      "dds.status_period_ms",                // DdsPoseSink's status period
      "dds.security.keystore",               // Service::check_keystore (keystore/)
      "dds.security.enclave",                // Service::check_keystore (keystore/)
      "camera.calibration_file",             // load_calibration_files (calibration/)
      "ceiling.map",                         // load_calibration_files (calibration/)
  };
  ASSERT_GT(v.fields.size(), 100u);
  for (const auto& f : v.fields) {
    const bool in_module = inside(f, c.pipeline) || inside(f, c.capture.device) ||
                           inside(f, c.capture.thread) || inside(f, c.ipc) ||
                           inside(f, c.dds.publisher) || inside(f, c.fleet);
    EXPECT_TRUE(in_module || daemon_keys.count(f.key) == 1)
        << f.key << " is bound to no module's options";
  }
}

TEST(ConfigSchema, DumpLoadsBackUnchanged) {
  ServiceConfig c = default_config();
  c.pipeline.intrinsics.fx = 612.25;
  c.dds.publisher.domain.peers = {"10.0.0.2", "10.0.0.3"};
  c.logging.level = LogLevel::kDebug;
  c.pipeline.positioning.mode = PositioningMode::kBarycentric;
  const std::string text = dump_config(c);
  auto loaded = load_config_string(text, "dump");
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_EQ(dump_config(*loaded), text);
}

}  // namespace
}  // namespace ceilpose
