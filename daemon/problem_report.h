#pragma once
// The periodic problem line of ceilposed: what grew since the last report,
// from the localizer's refusal histogram and the sinks' failed writes, e.g.
// "last 10.0 s: 37 frames without a red/green rectangle pair, 2 writes failed".
// Control thread only; reads counters that the pipeline thread writes.
#include <cstdint>
#include <string>

#include "core/refusal.h"

namespace ceilpose::daemon {

class ProblemReport {
 public:
  // The line for the counts now (empty when nothing grew); remembers them.
  std::string update(const RefusalHistogram::Counts& refusals, uint64_t write_failures);
  // update(), logged as one warning when not empty.
  void report(const RefusalHistogram::Counts& refusals, uint64_t write_failures, double interval_s);

 private:
  RefusalHistogram::Counts reported_{};
  uint64_t reported_failures_ = 0;
};

}  // namespace ceilpose::daemon
