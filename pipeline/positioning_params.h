#pragma once
// Parameters of the positioning stages and the temporal filter.
namespace ceilpose {

struct PositioningParams {
  int lsq_max_iterations = 10;  // Gauss-Newton iterations of the least-squares solver
};

struct FilterParams {
  bool enabled = true;  // the daemon filters; `locate` only with --filter
};

}  // namespace ceilpose
