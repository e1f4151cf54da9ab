#pragma once
// What the daemon's fleet keeps and when it gives up on a robot (SPEC §12;
// configuration section `fleet`, docs/fleet.md).
#include <cstdint>
#include <string>
#include <vector>

namespace ceilpose {

struct FleetOptions {
  bool enabled = true;
  // Only these robots (ROS names); empty: every robot on the domain.
  std::vector<std::string> robots;
  // Slots of the fleet segment; robots beyond it are refused and counted.
  uint32_t capacity = 256;
  // A robot with no sample for this long (or whose writer left) is stale...
  int stale_after_ms = 1000;
  // ...and is removed after this long without one.
  int remove_after_ms = 10000;
  // Clocks of two robots may differ by this much (chrony on a LAN keeps them
  // within 1 ms): a sample stamped further ahead is "from the future", one
  // older than this plus stale_after_ms "from the past"; both are refused.
  int max_clock_offset_ms = 200;
  // Samples a reader keeps per robot between two passes of the fleet thread.
  int history_depth = 8;
};

}  // namespace ceilpose
