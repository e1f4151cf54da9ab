#pragma once
// What the synthetic camera asks for: an image of the instant `elapsed_ns`
// after the stream started, and the robot pose it shows. capture/ calls it
// without knowing what makes the image; ceilposed and the tools wire it to
// the simulator (sim/trajectory_camera.h). Here, in core/, so that neither
// capture nor sim depends on the other.
#include <cstdint>
#include <string>

#include "core/camera_model.h"
#include "core/image.h"
#include "core/pose.h"

namespace ceilpose {

class FrameGenerator {
 public:
  virtual ~FrameGenerator() = default;
  // Size and lens of the images (fixed for the generator's life).
  virtual const CameraIntrinsics& intrinsics() const = 0;
  // The pixel format of the images, as a camera hands them over.
  virtual PixelFormat format() const { return PixelFormat::kRgb24; }
  // Renders into `out` (format(), intrinsics' size, already allocated by the
  // caller) the view at `elapsed_ns` since the start; `tick` numbers the
  // camera's exposures (noise seeds). Called from one thread; no allocation.
  virtual void generate(int64_t elapsed_ns, uint64_t tick, Image* out, Pose2D* ground_truth) = 0;
  // For logs and status: "seed 1".
  virtual std::string describe() const = 0;
};

}  // namespace ceilpose
