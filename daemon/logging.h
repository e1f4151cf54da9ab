#pragma once
// Logging of ceilposed through spdlog. Under systemd (JOURNAL_STREAM set, or
// stderr not a terminal) every line is "<N>message": journald reads the
// sd-daemon priority prefix and adds its own timestamp, so none is printed.
// At a terminal: local time, colour by level.
//
// Per-frame code never logs: it counts (ProblemCounters) and the control
// thread reports the counts at most once per interval.
#include <spdlog/spdlog.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <string>

#include "config/service_config.h"

namespace ceilpose::daemon {

enum class LogTarget { kJournal, kTerminal };

// The target the environment calls for (see above).
LogTarget detect_log_target();

// Installs the default spdlog logger for `target` (stderr). Call once, first.
void setup_logging(LogTarget target, LogLevel level);
void set_log_level(LogLevel level);
spdlog::level::level_enum to_spdlog(LogLevel level);

// "<3>" for spdlog's err, etc. (sd-daemon.h SD_ERR ...).
const char* journal_prefix(spdlog::level::level_enum level);

// Kinds of per-frame trouble, counted by the pipeline thread.
enum class Problem : int {
  kNoMarkers,      // frame processed, no marker decoded
  kInvalidPose,    // markers seen, but no pose
  kWrongHeights,   // no pose: the markers' spacing contradicts the configured heights
  kPublishFailed,  // DDS write failed
  kCount,
};
const char* to_string(Problem problem);

// Single writer (pipeline thread) increments; the control thread reports
// what accumulated since its last report. Lock-free, allocation-free.
class ProblemCounters {
 public:
  void count(Problem p) noexcept {
    counts_[static_cast<int>(p)].fetch_add(1, std::memory_order_relaxed);
  }
  uint64_t total(Problem p) const noexcept {
    return counts_[static_cast<int>(p)].load(std::memory_order_relaxed);
  }
  // Logs one warning line listing each problem that grew since the last call
  // (e.g. "last 10.0 s: 37 frames without markers, 2 DDS writes failed").
  void report(double interval_s);

 private:
  std::array<std::atomic<uint64_t>, static_cast<int>(Problem::kCount)> counts_{};
  std::array<uint64_t, static_cast<int>(Problem::kCount)> reported_{};
};

}  // namespace ceilpose::daemon
