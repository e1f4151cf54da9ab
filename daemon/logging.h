#pragma once
// Logging of ceilposed through spdlog. Under systemd (JOURNAL_STREAM set, or
// stderr not a terminal) every line is "<N>message": journald reads the
// sd-daemon priority prefix and adds its own timestamp, so none is printed.
// At a terminal: local time, colour by level.
//
// Per-frame code never logs: it counts (the localizer's refusal histogram)
// and the control thread reports the counts at most once per interval
// (daemon/problem_report.h).
#include <spdlog/spdlog.h>

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

}  // namespace ceilpose::daemon
