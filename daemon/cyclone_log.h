#pragma once
// Cyclone DDS writes its own warnings and errors straight to stderr, past the
// daemon's non-blocking log writer and without limit: 25k malformed datagrams
// made 19,094 lines (7.4 MB) in 6 s. route_cyclone_log() sends them through
// spdlog instead, at most a burst then a steady rate, and says how many it
// dropped.
#include <cstdint>
#include <mutex>

namespace ceilpose::daemon {

// A token bucket: `burst` lines at once, then `per_s` a second. Thread-safe
// (Cyclone logs from its receive threads).
class LogRateLimit {
 public:
  LogRateLimit(int burst, double per_s);
  // Whether a line at `now_ns` may be written; when it may, `*dropped` is the
  // number refused since the last one admitted.
  bool admit(int64_t now_ns, uint64_t* dropped);
  // The lines refused since the last one admitted, now counted as told.
  uint64_t take_dropped();

 private:
  std::mutex mutex_;
  const double burst_;
  const double per_ns_;
  double tokens_;
  int64_t last_ns_ = INT64_MIN;
  uint64_t dropped_ = 0;
};

// Cyclone's warnings and errors from now on go to spdlog as "dds: ...", at
// most 20 lines then 1 a second. Call once, after setup_logging().
void route_cyclone_log();
// Logs how many of Cyclone's lines were dropped since the last line or call,
// if any: a flood that stopped is still counted. The control thread calls it
// with its problem report.
void report_dropped_cyclone_lines();

}  // namespace ceilpose::daemon
