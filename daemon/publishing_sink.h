#pragma once
// The daemon's outputs (shared memory, DDS): each takes every localized frame
// (PoseSink) and, at its own period, the service's health.
#include <cstdint>

#include "capture/capture_thread.h"
#include "capture/latency_histogram.h"
#include "core/fix_state.h"
#include "core/refusal.h"
#include "pipeline/localizer.h"
#include "pipeline/pose_estimate.h"
#include "pipeline/pose_sink.h"

namespace ceilpose::daemon {

// The health every status output reports, assembled once per status tick by
// the pipeline thread.
struct ServiceStatus {
  int64_t now_ns = 0;  // CLOCK_MONOTONIC
  double fps = 0.0;
  capture::CaptureStats capture;
  capture::LatencySummary latency;  // capture -> published
  bool source_failed = false;
  const char* source = "";  // the capture source's description
  FixState fix = FixState::kNone;
  PositioningMode mode = PositioningMode::kAuto;  // of the latest published pose
  int markers = 0;                                // of the latest published pose
  RefusalHistogram::Counts refusals{};            // frames per refusal since start
  SweepCounts sweeps;                             // frames tracked / swept whole since start
};

class PublishingSink : public PoseSink {
 public:
  // Called from the pipeline thread every status_period_ns().
  virtual void publish_status(const ServiceStatus& status) = 0;
  virtual int64_t status_period_ns() const = 0;
  // Writes that failed since start (any thread may read).
  virtual uint64_t failures() const { return 0; }
};

}  // namespace ceilpose::daemon
