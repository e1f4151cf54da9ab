#pragma once
// How well the filtered pose follows a moving robot: the published pose at
// its frame's time, the filter's velocity, and the pose predicted a fixed
// time ahead (what a controller gets when the frame is that old), each
// against the ground truth at the instant it claims. Offline only: `evaluate
// --filter` and the moving-robot tests. The true velocity is the central
// difference of the neighbouring frames' ground truth; the truth at a
// predicted instant is interpolated between the frames around it.
#include <cstdint>
#include <vector>

#include "core/pose.h"
#include "pipeline/pose_sink.h"

namespace ceilpose {

struct MotionReport {
  int frames = 0;                // frames with ground truth and a valid filtered pose
  double median_error_mm = 0.0;  // filtered pose at the frame's time
  double p99_error_mm = 0.0;
  double max_error_mm = 0.0;
  double yaw_p99_deg = 0.0;
  int velocity_frames = 0;  // ... of which with a neighbour on each side
  double velocity_median_error_mps = 0.0;
  double velocity_p99_error_mps = 0.0;
  double yaw_rate_median_error_radps = 0.0;
  double predict_ms = 0.0;
  int predicted_frames = 0;  // frames whose predicted instant lies within the truth
  double predicted_median_error_mm = 0.0;
  double predicted_p99_error_mm = 0.0;
  double predicted_max_error_mm = 0.0;
  double predicted_yaw_p99_deg = 0.0;
  // The same instants had the frame's pose been used unpredicted.
  double unpredicted_p99_error_mm = 0.0;
};

class MotionAccuracySink final : public PoseSink {
 public:
  // The first settle_frames frames with ground truth are not scored (the
  // filter starts at rest: its first predictions are off by v·predict_ms).
  explicit MotionAccuracySink(double predict_ms, int settle_frames = 0)
      : predict_ms_(predict_ms), settle_frames_(settle_frames) {}
  void consume(const Localization& loc) override;
  MotionReport report() const;

 private:
  struct Truth {
    int64_t t_ns;
    Pose2D pose;
  };
  struct Sample {
    size_t truth;  // index into truth_
    Pose2D pose;
    double vx_mps, vy_mps, yaw_rate_radps;
    Pose2D predicted;
  };
  double predict_ms_;
  int settle_frames_;
  std::vector<Truth> truth_;
  std::vector<Sample> samples_;
};

}  // namespace ceilpose
