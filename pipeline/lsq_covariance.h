#pragma once
// The covariance of a least-squares pose: the residuals' scatter through the
// normal equations, the markers' placement (the map's sigmas and the scatter
// the markers show about their mapped places), carried from the camera to
// the robot through the mount, plus the configured floors.
#include <array>
#include <span>

#include "pipeline/change_of_axes.h"
#include "pipeline/lsq_terms.h"
#include "pipeline/marker_observation.h"

namespace ceilpose {

// Holds its per-marker work arrays: allocation-free. One per solver.
class LsqCovariance {
 public:
  // The robot's (x_m, y_m, yaw_rad) covariance, row-major, at the solution
  // `st` with normal equations `a` (priors included) and the Huber-weighted
  // squared residuals wr2 of n residuals. `consistent`: the markers grid
  // consistency kept (the solve may have rejected some of them since), `use`:
  // those the solve kept. `terms`: what the accumulate that gave `a` kept
  // of each point at `st` (empty: none; else at least one a point). False
  // when the normal equations are singular.
  bool robot_covariance(const ViewGeometry& view, const PositioningParams& params,
                        const LsqModel& model, std::span<const LsqPoint> points,
                        std::span<const PointTerms> terms, std::span<const MarkerFix> fixes,
                        std::span<const bool> consistent, std::span<const bool> use,
                        const LsqState& st, const LsqNormal& a, double wr2, int n,
                        const Pose2D& robot, std::array<double, 9>* out);

 private:
  LsqNormal placement_information(const ViewGeometry& view, const PositioningParams& params,
                                  std::span<const LsqPoint> points,
                                  std::span<const PointTerms> terms,
                                  std::span<const MarkerFix> fixes,
                                  std::span<const bool> consistent, std::span<const bool> use,
                                  const LsqState& st, const LsqModel& model);

  // Per marker: B_k (kLsqParams x 3, row-major), and J_m^T J_m, J_m^T r of
  // its own placement parameters (centre x, y, rotation).
  struct MarkerTerm {
    std::array<double, kLsqParams * 3> b{};
    std::array<double, 9> jtj{};
    std::array<double, 3> jtr{};
    int points = 0;
  };
  std::array<MarkerTerm, kMaxMarkersPerFrame> marker_terms_{};
};

}  // namespace ceilpose
