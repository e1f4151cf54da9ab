#pragma once
// A reader of the fleet segment (the C client, ceilposectl fleet --shm,
// tests): every neighbour, each carried to one instant by the same motion
// model and horizon as the own pose (predict_pose).
//
// Threads: one thread per reader. read(), find() and info() never allocate,
// wait or throw.
#include <cstdint>
#include <memory>
#include <string>

#include "core/result.h"
#include "ipc/shm/fleet_layout.h"
#include "ipc/shm/shm_common.h"

namespace ceilpose {

using FleetInfo = ::ceilpose_fleet_info;

class ShmFleetReader {
 public:
  // Opens fleet_segment_name(shm_name) read-only; checks magic, ABI and size.
  static Result<ShmFleetReader> open(const std::string& shm_name, shm::ShmErrc* code = nullptr);

  ShmFleetReader(ShmFleetReader&&) noexcept;
  ShmFleetReader& operator=(ShmFleetReader&&) noexcept;
  ~ShmFleetReader();

  // Up to max_robots robots into out, in slot order; returns how many.
  // t_mono_ns != 0: each predicted to that instant (CEILPOSE_FLEET_PREDICTED
  // or CEILPOSE_FLEET_NOT_PREDICTED).
  uint32_t read(int64_t t_mono_ns, shm::FleetRecord* out, uint32_t max_robots) const;
  // The robot named `robot`; false when no slot holds it.
  bool find(const char* robot, int64_t t_mono_ns, shm::FleetRecord* out) const;
  FleetInfo info() const;
  const std::string& name() const;

 private:
  struct Impl;
  explicit ShmFleetReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace ceilpose
