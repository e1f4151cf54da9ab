#include "daemon/cyclone_log.h"

#include <dds/dds.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <string_view>

#include "core/clock.h"

namespace ceilpose::daemon {
namespace {

constexpr int kBurstLines = 20;
constexpr double kLinesPerS = 1.0;

spdlog::level::level_enum level_of(uint32_t priority) {
  if ((priority & (DDS_LC_FATAL | DDS_LC_ERROR)) != 0) return spdlog::level::err;
  if ((priority & DDS_LC_WARNING) != 0) return spdlog::level::warn;
  if ((priority & DDS_LC_INFO) != 0) return spdlog::level::info;
  return spdlog::level::debug;
}

void log_dropped(uint64_t dropped) {
  spdlog::warn("dds: {} messages of Cyclone DDS dropped (rate limit {} a second)", dropped,
               kLinesPerS);
}

void write_cyclone_line(void* limit, const dds_log_data_t* data) {
  uint64_t dropped = 0;
  if (!static_cast<LogRateLimit*>(limit)->admit(monotonic_ns(), &dropped)) return;
  // Cyclone's own header (time, thread) is hdrsize long; spdlog adds ours.
  std::string_view text(data->message, data->size);
  text.remove_prefix(std::min(data->hdrsize, text.size()));
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.remove_suffix(1);
  if (dropped > 0) log_dropped(dropped);
  spdlog::log(level_of(data->priority), "dds: {}", text);
}

}  // namespace

LogRateLimit::LogRateLimit(int burst, double per_s)
    : burst_(burst), per_ns_(per_s * 1e-9), tokens_(burst) {}

bool LogRateLimit::admit(int64_t now_ns, uint64_t* dropped) {
  std::lock_guard lock(mutex_);
  if (last_ns_ != INT64_MIN && now_ns > last_ns_)
    tokens_ = std::min(burst_, tokens_ + static_cast<double>(now_ns - last_ns_) * per_ns_);
  last_ns_ = std::max(last_ns_, now_ns);
  if (tokens_ < 1.0) {
    ++dropped_;
    return false;
  }
  tokens_ -= 1.0;
  *dropped = dropped_;
  dropped_ = 0;
  return true;
}

uint64_t LogRateLimit::take_dropped() {
  std::lock_guard lock(mutex_);
  const uint64_t dropped = dropped_;
  dropped_ = 0;
  return dropped;
}

namespace {
LogRateLimit& cyclone_limit() {
  static LogRateLimit limit(kBurstLines, kLinesPerS);  // lives as long as Cyclone may log
  return limit;
}
}  // namespace

void route_cyclone_log() { dds_set_log_sink(&write_cyclone_line, &cyclone_limit()); }

void report_dropped_cyclone_lines() {
  if (const uint64_t dropped = cyclone_limit().take_dropped(); dropped > 0) log_dropped(dropped);
}

}  // namespace ceilpose::daemon
