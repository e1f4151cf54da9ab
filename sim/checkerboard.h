#pragma once
// A planar checkerboard held in front of the camera, for `ceilposectl
// calibrate camera` tests with known truth: the board at any pose, seen
// through the camera model of SPEC §3 (distortion included), anti-aliased by
// supersampling, and a set of views that covers the image at varied tilts.
#include <cstdint>
#include <vector>

#include "core/camera_model.h"
#include "core/image.h"

namespace ceilpose::sim {

struct Checkerboard {
  int cols = 9;  // inner corners, as OpenCV counts them
  int rows = 6;
  double square_m = 0.03;
};

// The board's pose in the camera frame: a board point (X, Y, 0) (X along
// the columns, Y along the rows, origin at the first inner corner) is at
// r_cb·(X, Y, 0) + t_c.
struct BoardPose {
  Mat3 r_cb{};
  Vec3 t_c{};
};

// Renders boards seen through one camera. The rays of every sub-sample are
// undistorted once, here (the distortion model is inverted iteratively).
class CheckerboardCamera {
 public:
  explicit CheckerboardCamera(const CameraIntrinsics& camera);
  // The board (white border of one square around the pattern) on a grey
  // background into `out` (RGB24, camera size), read noise sigma `noise`
  // levels. Deterministic in `seed`.
  void render(const Checkerboard& board, const BoardPose& pose, double noise, uint64_t seed,
              Image* out) const;

 private:
  CameraIntrinsics camera_;
  std::vector<float> rays_;  // undistorted normalized (x, y) per sub-sample
};

// `count` board poses at 0.35-0.9 m, tilted 10-45° in varied directions,
// spread over the image (the pattern inside the frame). Deterministic.
std::vector<BoardPose> checkerboard_views(const CameraIntrinsics& camera, const Checkerboard& board,
                                          int count, uint64_t seed);

}  // namespace ceilpose::sim
