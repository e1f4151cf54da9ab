#include "daemon/logging.h"

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/base_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <sys/stat.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <mutex>

#include "daemon/nonblocking_write.h"

namespace ceilpose::daemon {
namespace {

// Writes "<N>" + the formatted message to stderr, unbuffered, one write per line
// so lines of different threads never interleave inside journald's stream.
// Never blocks: a stderr pipe nobody reads loses lines instead of stopping
// the thread that logs (nonblocking_write.h).
class JournalSink : public spdlog::sinks::base_sink<std::mutex> {
 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    spdlog::memory_buf_t formatted;
    const char* prefix = journal_prefix(msg.level);
    formatted.append(prefix, prefix + 3);
    spdlog::memory_buf_t body;
    formatter_->format(msg, body);
    formatted.append(body.data(), body.data() + body.size());
    (void)write_without_blocking(STDERR_FILENO, formatted.data(), formatted.size());
  }
  void flush_() override {}
};

// True when stderr is the stream JOURNAL_STREAM names ("<dev>:<inode>"), the
// way systemd tells a service that its stderr goes to the journal.
bool stderr_is_journal_stream() {
  const char* env = std::getenv("JOURNAL_STREAM");
  if (env == nullptr) return false;
  unsigned long long dev = 0, ino = 0;
  if (std::sscanf(env, "%llu:%llu", &dev, &ino) != 2) return false;
  struct stat st {};
  if (fstat(STDERR_FILENO, &st) != 0) return false;
  return st.st_dev == dev && st.st_ino == ino;
}

}  // namespace

LogTarget detect_log_target() {
  if (stderr_is_journal_stream() || !isatty(STDERR_FILENO)) return LogTarget::kJournal;
  return LogTarget::kTerminal;
}

const char* journal_prefix(spdlog::level::level_enum level) {
  switch (level) {
    case spdlog::level::trace:
    case spdlog::level::debug:
      return SD_DEBUG;
    case spdlog::level::info:
      return SD_INFO;
    case spdlog::level::warn:
      return SD_WARNING;
    case spdlog::level::err:
      return SD_ERR;
    case spdlog::level::critical:
      return SD_CRIT;
    default:
      return SD_NOTICE;
  }
}

spdlog::level::level_enum to_spdlog(LogLevel level) {
  switch (level) {
    case LogLevel::kTrace:
      return spdlog::level::trace;
    case LogLevel::kDebug:
      return spdlog::level::debug;
    case LogLevel::kInfo:
      return spdlog::level::info;
    case LogLevel::kWarn:
      return spdlog::level::warn;
    case LogLevel::kError:
      return spdlog::level::err;
    case LogLevel::kCritical:
      return spdlog::level::critical;
    case LogLevel::kOff:
      return spdlog::level::off;
  }
  return spdlog::level::info;
}

void setup_logging(LogTarget target, LogLevel level) {
  std::shared_ptr<spdlog::logger> logger;
  if (target == LogTarget::kJournal) {
    auto sink = std::make_shared<JournalSink>();
    sink->set_pattern("%v");
    logger = std::make_shared<spdlog::logger>("ceilposed", sink);
  } else {
    auto sink = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
    sink->set_pattern("%H:%M:%S.%e %^%-5l%$ %v");
    logger = std::make_shared<spdlog::logger>("ceilposed", sink);
  }
  logger->set_level(to_spdlog(level));
  // Warnings and worse reach the journal at once, even if the daemon dies next.
  logger->flush_on(spdlog::level::warn);
  spdlog::set_default_logger(logger);
}

void set_log_level(LogLevel level) { spdlog::default_logger()->set_level(to_spdlog(level)); }

}  // namespace ceilpose::daemon
