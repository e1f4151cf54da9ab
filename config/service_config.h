#pragma once
// The daemon's whole configuration: what config/ceilpose.yaml holds. Defaults
// are SPEC.md's and live in the member initialisers here and in the structs of
// pipeline/ and core/; config/ceilpose.yaml documents the same values (a test
// checks that file and default_config() agree).
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "calibration/calibration_files.h"
#include "capture/capture_thread.h"
#include "capture/frame_source.h"
#include "core/result.h"
#include "ipc/dds/dds_options.h"
#include "ipc/fleet/fleet_options.h"
#include "ipc/shm/shm_pose_writer.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/pose_estimate.h"

namespace ceilpose {

// Where frames come from and how the capture and pipeline threads run. The
// source's and the capture thread's settings are capture's own option structs
// (their defaults are the configuration's); the frame size is camera.width x
// camera.height, the size the intrinsics are calibrated at.
struct CaptureConfig {
  std::string source = "synthetic";  // capture/source_spec.h, SPEC §7
  capture::SourceOptions device;  // rate, pixel formats, buffers, control locks, recovery, replay
  capture::CaptureThreadOptions thread;  // SCHED_FIFO priority and CPU of the capture thread
  // SCHED_FIFO priority of the pipeline thread: below the capture thread's so
  // that a frame is never lost to localization, above ordinary load so that a
  // busy machine does not delay the pose. 0 = normal scheduling.
  int pipeline_rt_priority = 40;
  uint64_t synthetic_seed = 1;  // noise seed of the synthetic camera
};

// DDS Security (SPEC §11): on when a keystore is named.
struct DdsSecurityConfig {
  std::string keystore_dir;  // "" = plain DDS
  std::string enclave;       // "" = the robot name
};

struct DdsConfig {
  bool enabled = true;
  // The publisher's own options (ipc/dds): robot name (empty = the host's,
  // resolved at start), domain id, interfaces, peers, reliability, history.
  DdsOptions publisher;
  int status_period_ms = 1000;  // period of the status topic (the DDS sink's)
  DdsSecurityConfig security;
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
  // camera.calibration_file and ceiling.map: loaded into `pipeline` by
  // load_calibration_files at start and on every reload.
  CalibrationFiles calibration;
  CaptureConfig capture;
  ShmOptions ipc;  // the shared-memory segment: name, group, stale_after_ms
  DdsConfig dds;
  FleetOptions fleet;  // the other robots' poses in <shm>-fleet (SPEC §12)
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
// Loads the files `config.calibration` names into config.pipeline (the
// capture size is camera.width x camera.height). Errors name the file.
Result<ServiceConfig> with_calibration_files(ServiceConfig config);

// Key paths whose values differ (what a SIGHUP reload changes); also
// "ceiling.map" when the map read from the same file has changed.
std::vector<std::string> changed_config_keys(const ServiceConfig& a, const ServiceConfig& b);

// What SIGHUP applies without a restart: the sections the pipeline thread
// can take between two frames (config_schema.h's kLiveSections), less the
// keys that fix buffers or the capture format (kRestartKeys). One table:
// the daemon, config/ceilpose.yaml's comments, the unit's comment and
// docs/service.md follow it (tests/config/live_keys_test.cpp).
bool is_live_key(std::string_view key_path);
// "the camera, mount, ... and logging keys live, but not camera.width and
// camera.height": the phrase every text about SIGHUP carries.
std::string live_keys_phrase();
// `running` with every live key taken from `next` (the loaded map and
// camera files with them), every other key left as it runs.
ServiceConfig with_live_keys(const ServiceConfig& running, const ServiceConfig& next);

// The configuration as YAML, every key present (`ceilposed --print-config`).
std::string dump_config(const ServiceConfig& config);

std::string_view to_string(LogLevel level);

}  // namespace ceilpose
