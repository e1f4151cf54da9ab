#pragma once
// SPEC §6 accuracy metrics of localized frames against ground truth; shared
// by `ceilposectl evaluate` and the golden accuracy tests. Offline only (it
// keeps every error to take percentiles).
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/pose.h"
#include "pipeline/pose_estimate.h"
#include "pipeline/pose_sink.h"

namespace ceilpose {

// Nearest-rank percentile (p in [0, 1]) of an ascending sample; 0 when empty.
double percentile(const std::vector<double>& sorted, double p);

struct AccuracyReport {
  int frames = 0;               // frames with ground truth
  int frames_with_whole = 0;    // ... of which with ≥ 1 whole marker in view
  int valid_with_whole = 0;     // ... of which with a valid pose
  int valid_without_whole = 0;  // valid poses where no whole marker was in view
  int valid = 0;                // valid poses (error statistics are over these)
  double availability = 0.0;    // valid_with_whole / frames_with_whole (1 when none)
  double within_both = 0.0;     // share of valid with |Δx| and |Δy| ≤ 0.05 grid units
  double within_x = 0.0;        // share with |Δx| ≤ 0.05 grid units (thesis, per axis)
  double within_y = 0.0;
  double median_error_mm = 0.0;  // straight-line position error
  double p99_error_mm = 0.0;
  double max_error_mm = 0.0;
  double yaw_p99_deg = 0.0;
  double yaw_max_deg = 0.0;
  int gross = 0;  // error > 0.25 grid units or yaw error > 5°
  // Mean normalised estimation error squared of (x, y, yaw) against the
  // reported covariance: 3 for an honest covariance, far above when it
  // claims too much, below when it claims too little. 0 when no frame had
  // an invertible covariance.
  double mean_nees = 0.0;
  double median_nees = 0.0;
  std::array<int, 4> mode_count{};  // valid poses per PositioningMode
};

class AccuracyAccumulator {
 public:
  explicit AccuracyAccumulator(double grid_m) : grid_m_(grid_m) {}

  // One frame: its ground truth, whether a whole marker was in view (SPEC §6
  // denominator of availability) and what was reported.
  void add(const Pose2D& truth, bool whole_marker_in_view, const PoseEstimate& estimate);
  AccuracyReport report() const;

 private:
  double grid_m_;
  AccuracyReport counts_;
  int within_both_ = 0, within_x_ = 0, within_y_ = 0;
  std::vector<double> error_m_;
  std::vector<double> yaw_error_rad_;
  std::vector<double> nees_;
};

// The accuracy scoring of a replay or a simulated run as a PoseSink: frames
// with ground truth are scored on their published pose. `whole_in_view`
// tells whether a whole marker was in view at a true pose (the availability
// denominator; the caller knows the camera and ceiling, e.g. the simulator's
// visibility).
class AccuracySink final : public PoseSink {
 public:
  AccuracySink(double grid_m, std::function<bool(const Pose2D&)> whole_in_view)
      : acc_(grid_m), whole_in_view_(std::move(whole_in_view)) {}
  void consume(const Localization& loc) override {
    if (loc.frame.has_ground_truth)
      acc_.add(loc.frame.ground_truth, whole_in_view_(loc.frame.ground_truth), loc.published);
  }
  AccuracyReport report() const { return acc_.report(); }

 private:
  AccuracyAccumulator acc_;
  std::function<bool(const Pose2D&)> whole_in_view_;
};

// One Markdown table row: set | availability | both axes | median / p99 |
// yaw p99 | gross.
std::string format_report_row(const std::string& name, const AccuracyReport& r);

}  // namespace ceilpose
