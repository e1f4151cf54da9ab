#include "sim/trajectory_camera.h"

#include "sim/camera_format.h"
#include "sim/trajectory.h"

namespace ceilpose::sim {

TrajectoryCamera::TrajectoryCamera(const TrajectoryCameraOptions& options)
    : options_(options), renderer_(options.scene) {
  if (options_.format != PixelFormat::kRgb24)
    rendered_.resize(options_.scene.intrinsics.width, options_.scene.intrinsics.height,
                     PixelFormat::kRgb24);
}

void TrajectoryCamera::generate(int64_t elapsed_ns, uint64_t tick, Image* out,
                                Pose2D* ground_truth) {
  const double t_s = options_.trajectory_start_s + static_cast<double>(elapsed_ns) * 1e-9;
  *ground_truth = trajectory_pose(options_.scene.layout, t_s);
  const uint64_t seed = options_.scene.seed * 1'000'003 + tick;
  if (options_.format == PixelFormat::kRgb24)
    return renderer_.render(*ground_truth, options_.mount, options_.effects, seed, out);
  renderer_.render(*ground_truth, options_.mount, options_.effects, seed, &rendered_);
  convert_rgb(rendered_, options_.format, out);
}

std::string TrajectoryCamera::describe() const {
  return "simulated ceiling, seed " + std::to_string(options_.scene.seed);
}

}  // namespace ceilpose::sim
