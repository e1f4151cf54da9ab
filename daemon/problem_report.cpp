#include "daemon/problem_report.h"

#include <spdlog/spdlog.h>

namespace ceilpose::daemon {

std::string ProblemReport::update(const RefusalHistogram::Counts& refusals,
                                  uint64_t write_failures) {
  std::string line;
  auto add = [&line](uint64_t delta, std::string_view what) {
    if (delta == 0) return;
    if (!line.empty()) line += ", ";
    line += std::to_string(delta) + " ";
    line += what;
  };
  for (int i = 0; i < kRefusalCount; ++i) {
    const auto r = static_cast<Refusal>(i);
    if (r != Refusal::kNone) add(refusals[i] - reported_[i], describe(r));
  }
  add(write_failures - reported_failures_, "DDS writes failed");
  reported_ = refusals;
  reported_failures_ = write_failures;
  return line;
}

void ProblemReport::report(const RefusalHistogram::Counts& refusals, uint64_t write_failures,
                           double interval_s) {
  const std::string line = update(refusals, write_failures);
  if (!line.empty()) spdlog::warn("last {:.1f} s: {}", interval_s, line);
}

}  // namespace ceilpose::daemon
