#include "sim/trajectory_camera.h"

#include "sim/trajectory.h"

namespace ceilpose::sim {

TrajectoryCamera::TrajectoryCamera(const TrajectoryCameraOptions& options)
    : options_(options), renderer_(options.scene) {}

void TrajectoryCamera::generate(int64_t elapsed_ns, uint64_t tick, Image* out,
                                Pose2D* ground_truth) {
  const double t_s = options_.trajectory_start_s + static_cast<double>(elapsed_ns) * 1e-9;
  *ground_truth = trajectory_pose(options_.scene.layout, t_s);
  renderer_.render(*ground_truth, options_.mount, options_.effects,
                   options_.scene.seed * 1'000'003 + tick, out);
}

std::string TrajectoryCamera::describe() const {
  return "simulated ceiling, seed " + std::to_string(options_.scene.seed);
}

}  // namespace ceilpose::sim
