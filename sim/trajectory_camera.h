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
  // As the camera hands frames over (sim/camera_format.h): RGB24, or YUYV,
  // NV12, ... converted from the render.
  PixelFormat format = PixelFormat::kRgb24;
};

class TrajectoryCamera final : public FrameGenerator {
 public:
  explicit TrajectoryCamera(const TrajectoryCameraOptions& options);

  const CameraIntrinsics& intrinsics() const override { return options_.scene.intrinsics; }
  PixelFormat format() const override { return options_.format; }
  void generate(int64_t elapsed_ns, uint64_t tick, Image* out, Pose2D* ground_truth) override;
  std::string describe() const override;

 private:
  TrajectoryCameraOptions options_;
  Renderer renderer_;
  Image rendered_;  // the RGB render of a frame in another format, sized once
};

}  // namespace ceilpose::sim
