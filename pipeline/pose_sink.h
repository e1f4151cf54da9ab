#pragma once
// A consumer of localized frames: shared memory and DDS in the daemon, JSON
// Lines and accuracy scoring offline. Every sink sees the same Localization.
#include "pipeline/localization.h"

namespace ceilpose {

class PoseSink {
 public:
  virtual ~PoseSink() = default;
  // Called once per frame, in frame order, from the localizing thread. In
  // the daemon this is the per-frame path: no allocation, no blocking.
  virtual void consume(const Localization& localization) = 0;
};

}  // namespace ceilpose
