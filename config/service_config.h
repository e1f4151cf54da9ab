#pragma once
// The daemon's whole configuration: what config/ceilpose.yaml holds. Defaults
// are SPEC.md's and live in the member initialisers here and in the structs of
// pipeline/ and core/; config/ceilpose.yaml documents the same values (a test
// checks that file and default_config() agree).
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/result.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/pose_estimate.h"

namespace ceilpose {

// Where frames come from and how the capture thread runs (issue 4).
struct CaptureConfig {
  // synthetic | replay:DIR | v4l2:/dev/videoN | libcamera[:ID]  (SPEC §7)
  std::string source = "synthetic";
  int width_px = 640;  // must equal camera.width: intrinsics are calibrated at one size
  int height_px = 480;
  double fps = 30.0;
  std::string pixel_format = "auto";  // auto | yuyv | mjpeg | rgb24 | bgr24 | gray8
  int buffer_count = 4;               // driver buffers (V4L2 mmap) and ring slots
  int rt_priority = 50;               // SCHED_FIFO priority of the capture thread; 0 = normal
  int cpu = -1;                       // CPU the capture thread is pinned to; -1 = any
  // SCHED_FIFO priority of the pipeline thread: below the capture thread's so
  // that a frame is never lost to localization, above ordinary load so that a
  // busy machine does not delay the pose. 0 = normal scheduling.
  int pipeline_rt_priority = 40;
  // Auto exposure, gain and white balance ruin colour thresholds (the thesis's
  // main failure), so a camera's are locked by default.
  bool lock_exposure = true;
  int exposure_us = 8000;  // exposure when locked; short to limit motion blur
  bool lock_gain = true;
  int gain = -1;  // analogue gain when locked, driver units; -1 = keep the driver's
  bool lock_white_balance = true;
  int white_balance_k = 4600;  // colour temperature when locked; office fluorescent light
  // Live-device recovery: no frame for this long is an outage; reopening backs
  // off exponentially between the two bounds.
  int stall_timeout_ms = 2000;
  int reconnect_initial_ms = 100;
  int reconnect_max_ms = 5000;
  double replay_speed = 1.0;  // 1 = recorded timing, 2 = twice as fast, 0 = as fast as possible
  bool replay_loop = false;
  uint64_t synthetic_seed = 1;  // noise seed of the synthetic camera
};

struct IpcConfig {
  std::string shm_name = "/ceilpose";  // POSIX shared-memory segment name
  std::string group;                   // group owning the segment (mode 0640); empty = ours
  int stale_after_ms = 500;            // readers call a pose stale after this long
};

struct DdsConfig {
  bool enabled = true;
  int domain_id = 0;
  std::string robot_name;               // empty = host name; topic rt/<robot_name>/pose
  bool reliable = true;                 // reliable, or best effort
  int history_depth = 10;               // ROS 2's default profile: keep last 10
  std::vector<std::string> interfaces;  // network interfaces; empty = Cyclone's choice
  std::vector<std::string> peers;       // unicast discovery peers; empty = multicast
  int status_period_ms = 1000;          // period of the status topic
};

enum class LogLevel : uint8_t { kTrace, kDebug, kInfo, kWarn, kError, kCritical, kOff };

struct LoggingConfig {
  LogLevel level = LogLevel::kInfo;
  // A per-frame problem (decode failure, dropped frame) is counted and
  // reported at most this often, never once per frame.
  int problem_report_interval_ms = 10000;
};

struct WatchdogConfig {
  // The systemd watchdog is only fed while the pipeline has finished a frame
  // within this long; a stalled pipeline or dead capture thread starves it.
  int max_stall_ms = 2000;
  int status_interval_ms = 1000;  // how often STATUS= and the shm status block refresh
};

struct ServiceConfig {
  PipelineConfig pipeline;
  PositioningMode positioning_mode = PositioningMode::kAuto;
  CaptureConfig capture;
  IpcConfig ipc;
  DdsConfig dds;
  LoggingConfig logging;
  WatchdogConfig watchdog;
};

ServiceConfig default_config();

// Reads and validates a YAML configuration. Keys left out keep their default;
// unknown keys, wrong types and out-of-range values are errors whose message
// names the file, the line, the key path (e.g. `camera.fx`), what was expected
// and what was found.
Result<ServiceConfig> load_config_file(const std::string& path);
// Same, from text; `origin` names the text in messages.
Result<ServiceConfig> load_config_string(const std::string& yaml_text, const std::string& origin);

// A command-line value for one key, checked like the file's (ceilposed
// --source sets capture.source, ...). `origin` names it in messages ("--source").
struct ConfigOverride {
  std::string key_path;
  std::string value;
  std::string origin;
};
Result<ServiceConfig> apply_overrides(const ServiceConfig& base,
                                      const std::vector<ConfigOverride>& overrides);

// Key paths (e.g. `camera.fx`) the schema knows but `yaml_text` leaves out.
// Lets a test prove the shipped file documents every key.
Result<std::vector<std::string>> missing_config_keys(const std::string& yaml_text,
                                                     const std::string& origin);

// Every key path the schema knows, in file order (e.g. `camera.fx`).
std::vector<std::string> config_key_paths();

// Every key with its value as YAML text ("camera.fx" -> "530.0"), file order.
std::vector<std::pair<std::string, std::string>> config_values(const ServiceConfig& config);
// Key paths whose values differ (what a SIGHUP reload changes).
std::vector<std::string> changed_config_keys(const ServiceConfig& a, const ServiceConfig& b);

// The configuration as YAML, every key present (`ceilposed --print-config`).
std::string dump_config(const ServiceConfig& config);

std::string_view to_string(LogLevel level);

}  // namespace ceilpose
