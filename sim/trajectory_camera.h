#pragma once
// The simulator as a frame generator for the synthetic camera: a robot
// following sim::trajectory_pose under the configured ceiling, seen through
// the configured camera and mount, with image effects.
#include <cstdint>
#include <string>

#include "core/frame_generator.h"
#include "sim/effects.h"
#include "sim/renderer.h"

namespace ceilpose::sim {

struct TrajectoryCameraOptions {
  SceneOptions scene;  // ceiling, camera model and seed
  CameraMount mount;
  Effects effects;
  double trajectory_start_s = 0.0;  // time along trajectory_pose of the first frame
};

class TrajectoryCamera final : public FrameGenerator {
 public:
  explicit TrajectoryCamera(const TrajectoryCameraOptions& options);

  const CameraIntrinsics& intrinsics() const override { return options_.scene.intrinsics; }
  void generate(int64_t elapsed_ns, uint64_t tick, Image* out, Pose2D* ground_truth) override;
  std::string describe() const override;

 private:
  TrajectoryCameraOptions options_;
  Renderer renderer_;
};

}  // namespace ceilpose::sim
