#pragma once
// The bytes of the fleet segment "<shm>-fleet" (CEILPOSE_FLEET_ABI_VERSION).
// docs/fleet.md draws the same layout for people writing other readers.
//
//   offset 0     FleetHeader   identity (written once, `magic` published last
//                              with release), writer state, heartbeat, counters
//   offset 192   slots[capacity]  SeqlockSlot<FleetRecord>, 1024 bytes each
//
// One writer (the daemon's fleet thread) fills the slots; a slot whose robot
// name is empty is free. The writer takes the lowest free slot for a new
// robot and keeps `slots_used` at one past the highest slot it ever used, so a
// reader scans only that many. The seqlock is shm_layout.h's.
#include <atomic>
#include <cstddef>
#include <cstdint>

#include "ceilpose/pose_client.h"
#include "core/ros_name.h"
#include "ipc/shm/shm_layout.h"

namespace ceilpose::shm {

inline constexpr uint64_t kFleetMagic = 0x54454c4650454c43ULL;  // "CLEPFLET" in memory order
inline constexpr uint32_t kFleetAbiVersion = CEILPOSE_FLEET_ABI_VERSION;
inline constexpr const char* kFleetSuffix = CEILPOSE_FLEET_SUFFIX;

using FleetRecord = ::ceilpose_fleet_robot;
static_assert(kMaxRobotNameLength < CEILPOSE_ROBOT_NAME_SIZE, "every robot name fits a slot");

struct alignas(64) FleetHeader {
  // Identity: written once before `magic` (release).
  std::atomic<uint64_t> magic;
  uint32_t abi_version;
  uint32_t header_size;
  uint64_t segment_size;
  uint32_t capacity;
  uint32_t slot_size;
  int32_t writer_pid;
  uint32_t stale_after_ms;
  uint64_t generation;
  int64_t start_mono_ns;
  int64_t start_real_ns;

  // Writer-owned, read by everybody.
  alignas(64) std::atomic<uint32_t> state;  // WriterState
  std::atomic<uint32_t> slots_used;         // one past the highest slot ever used
  std::atomic<int64_t> heartbeat_mono_ns;
  std::atomic<uint32_t> robots;  // slots holding a robot now
  uint32_t reserved0;
  // Counters, ceilpose_fleet_info's order.
  std::atomic<uint64_t> accepted;
  std::atomic<uint64_t> refused_full;
  std::atomic<uint64_t> refused_future;
  std::atomic<uint64_t> refused_past;
  std::atomic<uint64_t> refused_invalid;
  std::atomic<uint64_t> refused_duplicate;
  std::atomic<uint64_t> removed;
};

using FleetSlot = SeqlockSlot<FleetRecord>;

inline constexpr size_t fleet_segment_size(uint32_t capacity) {
  return sizeof(FleetHeader) + size_t{capacity} * sizeof(FleetSlot);
}

inline FleetSlot* fleet_slots(FleetHeader* header) {
  return reinterpret_cast<FleetSlot*>(reinterpret_cast<char*>(header) + sizeof(FleetHeader));
}
inline const FleetSlot* fleet_slots(const FleetHeader* header) {
  return reinterpret_cast<const FleetSlot*>(reinterpret_cast<const char*>(header) +
                                            sizeof(FleetHeader));
}

static_assert(sizeof(FleetHeader) == 192, "layout of docs/fleet.md");
static_assert(offsetof(FleetHeader, abi_version) == 8, "layout of docs/fleet.md");
static_assert(offsetof(FleetHeader, capacity) == 24, "layout of docs/fleet.md");
static_assert(offsetof(FleetHeader, writer_pid) == 32, "layout of docs/fleet.md");
static_assert(offsetof(FleetHeader, generation) == 40, "layout of docs/fleet.md");
static_assert(offsetof(FleetHeader, state) == 64, "layout of docs/fleet.md");
static_assert(offsetof(FleetHeader, slots_used) == 68, "layout of docs/fleet.md");
static_assert(offsetof(FleetHeader, heartbeat_mono_ns) == 72, "layout of docs/fleet.md");
static_assert(offsetof(FleetHeader, robots) == 80, "layout of docs/fleet.md");
static_assert(offsetof(FleetHeader, accepted) == 88, "layout of docs/fleet.md");
static_assert(offsetof(FleetHeader, removed) == 136, "layout of docs/fleet.md");
static_assert(sizeof(FleetSlot) == 1024, "layout of docs/fleet.md");

}  // namespace ceilpose::shm
