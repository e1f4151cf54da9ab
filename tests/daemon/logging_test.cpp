#include "daemon/logging.h"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <systemd/sd-daemon.h>

#include <sstream>

#include "daemon/cyclone_log.h"
#include "daemon/problem_report.h"

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

RefusalHistogram::Counts counts_with(std::initializer_list<std::pair<Refusal, uint64_t>> counts) {
  RefusalHistogram::Counts c{};
  for (const auto& [r, n] : counts) c[static_cast<size_t>(r)] = n;
  return c;
}

TEST(ProblemReport, ReportsManyFramesAsOneLineWithTheRefusalsDescription) {
  CapturedLog log;
  ProblemReport report;
  report.report(counts_with({{Refusal::kNone, 50}, {Refusal::kNoMarkers, 1000}}), 1, 10.0);
  const std::string text = log.text();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  EXPECT_NE(text.find("last 10.0 s: 1000 " + std::string(describe(Refusal::kNoMarkers))),
            std::string::npos)
      << text;
  EXPECT_NE(text.find(", 1 DDS writes failed"), std::string::npos) << text;
  EXPECT_EQ(text.find(std::string(describe(Refusal::kNone))), std::string::npos)
      << "frames with a pose are no problem: " << text;
}

TEST(ProblemReport, ReportsOnlyWhatGrewSinceTheLastReport) {
  ProblemReport report;
  EXPECT_EQ(report.update(counts_with({{Refusal::kNoMarkers, 1}}), 0),
            "1 " + std::string(describe(Refusal::kNoMarkers)));
  EXPECT_EQ(report.update(counts_with({{Refusal::kNoMarkers, 1}}), 0), "") << "nothing new";
  EXPECT_EQ(report.update(counts_with({{Refusal::kNoMarkers, 1}, {Refusal::kWrongHeights, 3}}), 0),
            "3 " + std::string(describe(Refusal::kWrongHeights)));
}

TEST(LogRateLimit, AdmitsABurstThenOneLineASecondAndCountsTheRest) {
  LogRateLimit limit(20, 1.0);
  uint64_t dropped = 99;
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(limit.admit(1'000, &dropped)) << i;
  EXPECT_EQ(dropped, 0u);
  for (int i = 0; i < 500; ++i) EXPECT_FALSE(limit.admit(1'000 + i, &dropped));
  EXPECT_FALSE(limit.admit(500'000'000, &dropped));  // half a second later: no token yet
  ASSERT_TRUE(limit.admit(1'000'001'000, &dropped));
  EXPECT_EQ(dropped, 501u);
  EXPECT_FALSE(limit.admit(1'000'002'000, &dropped));
  EXPECT_EQ(limit.take_dropped(), 1u);
  EXPECT_EQ(limit.take_dropped(), 0u);
}

TEST(LogRateLimit, AClockThatStepsBackDoesNotMintTokens) {
  LogRateLimit limit(1, 1.0);
  uint64_t dropped = 0;
  ASSERT_TRUE(limit.admit(10'000'000'000, &dropped));
  EXPECT_FALSE(limit.admit(1'000, &dropped));
  EXPECT_FALSE(limit.admit(10'000'000'000, &dropped));
}

}  // namespace
}  // namespace ceilpose::daemon
