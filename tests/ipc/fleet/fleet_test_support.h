#pragma once
// Samples and segments for the fleet tests.
#include <unistd.h>

#include <atomic>
#include <string>

#include "core/clock.h"
#include "ipc/shm/pose_record.h"

namespace ceilpose::test {

inline constexpr int64_t kMs = 1'000'000;
// A realtime clock 1.7e18 ns since the epoch and the monotonic clock as the
// process started (readers judge ages on the real one): the offset between
// them is what the keeper must take out.
inline constexpr int64_t kRealNow = 1'700'000'000'000'000'000;
inline const int64_t kMonoNow = monotonic_ns();

// A filtered pose with motion (0.5 m/s east), stamped at `real_ns`.
inline PoseRecord moving_pose(int64_t real_ns, double x_m, uint64_t seq = 1) {
  PoseRecord p{};
  p.seq = seq;
  p.capture_real_ns = real_ns;
  p.x_m = x_m;
  p.y_m = 2.0;
  p.yaw_rad = 0.3;
  p.covariance[0] = p.covariance[4] = 1e-6;
  p.covariance[8] = 1e-5;
  p.flags = kPoseValid | kPoseFiltered | kPoseMotion;
  p.mode = CEILPOSE_MODE_LSQ;
  p.markers = 5;
  p.vx_mps = 0.5;
  for (int i = 0; i < CEILPOSE_STATE_SIZE; ++i)
    p.state_covariance[i * CEILPOSE_STATE_SIZE + i] = 1e-4;
  p.jerk_density[0] = p.jerk_density[1] = 1.0;
  p.jerk_density[2] = 0.5;
  p.predict_horizon_ms = 500;
  return p;
}

inline std::string unique_fleet_shm() {
  static std::atomic<int> n{0};
  return "/ceilpose-fleettest-" + std::to_string(::getpid()) + "-" + std::to_string(n++);
}

}  // namespace ceilpose::test
