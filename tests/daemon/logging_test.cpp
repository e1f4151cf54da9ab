#include "daemon/logging.h"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <systemd/sd-daemon.h>

#include <sstream>

namespace ceilpose::daemon {
namespace {

// Captures what the default logger prints during a test.
class CapturedLog {
 public:
  CapturedLog() : previous_(spdlog::default_logger()) {
    auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(text_);
    sink->set_pattern("%l %v");
    spdlog::set_default_logger(std::make_shared<spdlog::logger>("test", sink));
  }
  ~CapturedLog() { spdlog::set_default_logger(previous_); }
  std::string text() const { return text_.str(); }

 private:
  std::ostringstream text_;
  std::shared_ptr<spdlog::logger> previous_;
};

TEST(JournalPrefix, MapsLevelsToSdDaemonPriorities) {
  EXPECT_STREQ(journal_prefix(spdlog::level::err), SD_ERR);
  EXPECT_STREQ(journal_prefix(spdlog::level::warn), SD_WARNING);
  EXPECT_STREQ(journal_prefix(spdlog::level::info), SD_INFO);
  EXPECT_STREQ(journal_prefix(spdlog::level::debug), SD_DEBUG);
  EXPECT_STREQ(journal_prefix(spdlog::level::critical), SD_CRIT);
}

TEST(ProblemCounters, ReportsManyFramesAsOneLine) {
  CapturedLog log;
  ProblemCounters counters;
  for (int i = 0; i < 1000; ++i) counters.count(Problem::kNoMarkers);
  counters.count(Problem::kPublishFailed);
  counters.report(10.0);
  const std::string text = log.text();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  EXPECT_NE(text.find("1000 frames without a decoded marker"), std::string::npos) << text;
  EXPECT_NE(text.find("1 DDS writes failed"), std::string::npos) << text;
}

TEST(ProblemCounters, ReportsOnlyWhatGrewSinceTheLastReport) {
  CapturedLog log;
  ProblemCounters counters;
  counters.count(Problem::kNoMarkers);
  counters.report(10.0);
  counters.report(10.0);  // nothing new: silent
  counters.count(Problem::kInvalidPose);
  counters.report(10.0);
  const std::string text = log.text();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 2) << text;
  EXPECT_EQ(text.find("frames without a decoded marker", text.find('\n')), std::string::npos)
      << text;
  EXPECT_EQ(counters.total(Problem::kNoMarkers), 1u);
}

}  // namespace
}  // namespace ceilpose::daemon
