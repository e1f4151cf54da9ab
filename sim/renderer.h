#pragma once
// Renders the upward camera's view of the SPEC ceiling (tiles, rails, every
// marker, light fixtures, clutter) for any robot pose and camera mount, with
// the photometric effects of `Effects`. The simulator is the project's test
// oracle: its geometry goes through core/camera_model.h so that it shares the
// conventions of SPEC §3 with the pipeline, and it is anti-aliased by area
// integration so that sub-pixel accuracy can be measured.
//
// Colour: SPEC's printed sRGB values are decoded to linear light, pixels are
// integrated there (area averages are only physical in linear light), and the
// camera model (photometry.h) re-encodes sRGB; a uniform area at unit gain
// shows exactly the printed value.
//
// Thread: one Renderer per thread (render() uses internal buffers).
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "core/camera_model.h"
#include "core/ceiling_layout.h"
#include "core/image.h"
#include "core/pose.h"
#include "sim/ceiling_scene.h"
#include "sim/effects.h"
#include "sim/photometry.h"

namespace ceilpose::sim {

struct SceneOptions {
  CeilingLayout layout;
  CameraIntrinsics intrinsics;
  uint64_t seed = 1;  // places fixtures and clutter; seeds the per-frame noise
  // Where the markers really are; null: the nominal grid (SPEC §1).
  std::shared_ptr<const LaidCeiling> laid;
};

// SPEC's default camera (640 x 480, fx = fy = 530) resized to `width_px`
// wide, 4:3, with the same field of view: the focal length scales with the
// width. For benchmarks and tests at 320 x 240, 1280 x 960, ...
CameraIntrinsics scaled_default_intrinsics(int width_px);

// Sub-samples per axis of a pixel that straddles an edge.
inline constexpr int kSupersamplePerAxis = 4;

class Renderer {
 public:
  explicit Renderer(const SceneOptions& options);

  // Renders the view of a robot at `robot` with camera `mount` into `out` (RGB24, intrinsics size).
  // Deterministic in (options.seed, frame_seed). Allocates only when out's size changes.
  void render(const Pose2D& robot, const CameraMount& mount, const Effects& effects,
              uint64_t frame_seed, Image* out);

  // The same through a rolling shutter (SPEC §3): pixel row v shows the
  // robot at pose_at(dt) with dt = (v - (height - 1)/2) / height * readout_s
  // seconds after the frame's time, the whole row at once. readout_s = 0
  // gives exactly render()'s image (one pose for every row).
  using PoseAt = std::function<Pose2D(double dt_s)>;
  void render_rolling(const PoseAt& pose_at, double readout_s, const CameraMount& mount,
                      const Effects& effects, uint64_t frame_seed, Image* out);

  // The ceiling point (x, y) that pixel (u, v) sees, through the same ray
  // mapping render() uses. False when the ray does not reach the ceiling.
  bool ceiling_point(const Pose2D& robot, const CameraMount& mount, double u_px, double v_px,
                     double* x_m, double* y_m) const;

  const SceneOptions& options() const { return options_; }
  const CeilingScene& scene() const { return scene_; }

 private:
  // Integrates every pixel row r as seen from camera pose pose_of_row(r)
  // (`one_map`: the same for every row) into linear_, then applies the
  // photometry.
  template <typename PoseOfRow>
  void render_rows(const PoseOfRow& pose_of_row, bool one_map, const Effects& effects,
                   uint64_t frame_seed, Image* out);

  SceneOptions options_;
  CeilingScene scene_;
  // Undistorted normalized coordinates (x, y) of every pixel corner,
  // (width+1) x (height+1), computed once: the distortion model is inverted
  // here and never per frame.
  std::vector<float> corner_xy_;
  std::vector<float> linear_;          // integrated radiance, width*height*3
  std::vector<CameraPose> row_poses_;  // render_rolling: the camera at each row's time
  std::vector<uint8_t> row_above_;     // materials at the corners above the current pixel row
  std::vector<uint8_t> row_below_;
  Photometry photometry_;
};

}  // namespace ceilpose::sim
