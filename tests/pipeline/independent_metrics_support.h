#pragma once
// SPEC §6's accuracy figures recomputed from its text for the cross-check
// (not taken from pipeline/accuracy_metrics, which the check must not trust).
// Shared by the in-process cases and the `ceilposectl locate` cases.
#include <optional>
#include <string>
#include <vector>

#include "independent_renderer_support.h"

namespace ceilpose::testing::xcheck {

constexpr double kGridUnit_m = 0.6096;

// Frames a case runs: all in Release, a sixth (at least 6) under ASan/TSan,
// where rendering dominates the suite's time.
int frames_for(int release_frames);

// Angle wrapped to [-pi, pi].
double wrapped_rad(double a_rad);

// The q-quantile (nearest rank) of `v`; 0 for an empty vector.
double percentile(std::vector<double> v, double q);

// SPEC §6 figures of one case, accumulated one frame at a time.
struct Spec6Figures {
  int frames = 0;
  int with_whole = 0;  // frames with a whole marker in view (availability's denominator)
  int valid_with_whole = 0;
  int valid = 0;
  int within_both = 0;  // valid poses with |dx| and |dy| <= 0.05 grid units
  int gross = 0;
  int yaw_out_of_range = 0;  // reported yaw outside (-pi, pi]
  int decoded = 0;           // filled in by callers that see the markers
  int wrong_codes = 0;
  std::vector<double> error_mm;
  std::vector<double> yaw_error_deg;
  // Signed error in the robot frame: a bent pixel or axis convention shows as a bias.
  double sum_forward_mm = 0.0;
  double sum_left_mm = 0.0;

  // One frame: the truth, whether a whole marker was in view, and the
  // reported pose (nullopt when the frame gave none).
  void add(const XPose& truth, bool whole_marker_in_view, const std::optional<XPose>& reported);

  double availability() const;
  double both_share() const;
  double bias_forward_mm() const;
  double bias_left_mm() const;
  double median_mm() const { return percentile(error_mm, 0.5); }
  double p99_mm() const { return percentile(error_mm, 0.99); }
  double max_mm() const { return percentile(error_mm, 1.0); }
  double yaw_p99_deg() const { return percentile(yaw_error_deg, 0.99); }
  double yaw_max_deg() const { return percentile(yaw_error_deg, 1.0); }

  // One `[tag] name frames ... ` line on stdout: what docs/cross_check.md quotes.
  void print(const char* tag, const std::string& name) const;
};

}  // namespace ceilpose::testing::xcheck
