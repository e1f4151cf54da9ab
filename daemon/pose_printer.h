#pragma once
// The text ceilposed shows people: one line per pose for --print-poses (with
// the source's ground truth and error when it knows them) and the systemd
// STATUS= line. Control thread only.
#include <cstdint>
#include <string>

#include "capture/latency_histogram.h"
#include "daemon/pipeline_worker.h"

namespace ceilpose::daemon {

// "fix fix, 9 markers, 30.0 fps, latency p50 0.41 ms p99 0.62 ms"
std::string status_line(const PoseSnapshot& s, const capture::FrameLatency& latency);

// One --print-poses line for `s` (times relative to start_ns), with '\n'.
std::string pose_line(const PoseSnapshot& s, int64_t start_ns);

// --print-poses onto stdout without ever blocking (nonblocking_write.h):
// lines the reader does not take are dropped and counted; a closed or
// failing stdout ends the printing, said once in the log.
class PosePrinter {
 public:
  explicit PosePrinter(int64_t start_ns) : start_ns_(start_ns) {}
  ~PosePrinter();  // says how many lines were lost, if any
  PosePrinter(const PosePrinter&) = delete;
  PosePrinter& operator=(const PosePrinter&) = delete;
  void print(const PoseSnapshot& s);
  uint64_t dropped() const { return dropped_; }
  bool stopped() const { return stopped_; }

 private:
  int64_t start_ns_;
  uint64_t printed_ = 0;
  uint64_t dropped_ = 0;
  bool stopped_ = false;
};

}  // namespace ceilpose::daemon
