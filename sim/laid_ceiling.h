#pragma once
// Where the markers of a simulated ceiling really are: the nominal grid of
// SPEC §1, or a ceiling laid by hand — every marker glued a little off its
// rail intersection and turned a little, one far off, some fallen off, one
// code printed twice. Deterministic from the seed. The truth a survey is
// measured against.
#include <cstdint>
#include <string>
#include <vector>

#include "core/ceiling_layout.h"
#include "core/ceiling_map.h"
#include "core/result.h"

namespace ceilpose::sim {

struct HandLaidOptions {
  double sigma_m = 0.015;               // per-axis offset of each marker, 1-sigma
  double sigma_yaw_rad = 0.0174532925;  // rotation of each marker, 1-sigma (1°)
  double outlier_m = 0.05;              // one marker this far off its spot (0: none)
  int missing = 1;                      // markers that fell off
  bool duplicate = true;                // one marker shows another's code
  uint64_t seed = 1;
};

// What is glued at grid node (i, j) (the rail intersection (i·g, j·g)).
struct LaidMarker {
  bool present = false;
  int code_i = 0;  // the code printed on it (the node's own, or a duplicate)
  int code_j = 0;
  double x_m = 0.0;  // its centre
  double y_m = 0.0;
  double yaw_rad = 0.0;  // its rotation from nominal, CCW
};

class LaidCeiling {
 public:
  // Every marker at its nominal place.
  explicit LaidCeiling(const CeilingLayout& layout);
  static LaidCeiling hand_laid(const CeilingLayout& layout, const HandLaidOptions& options);
  // "nominal" or "hand-laid[:SIGMA_MM[:SIGMA_DEG]]" (seed from `seed`).
  static Result<LaidCeiling> parse(const std::string& spec, const CeilingLayout& layout,
                                   uint64_t seed);

  int side() const { return side_; }
  const LaidMarker& at(int i, int j) const {
    return nodes_[static_cast<size_t>(j) * static_cast<size_t>(side_) + static_cast<size_t>(i)];
  }
  // The true map (SPEC §8): every marker on the ceiling by the code it shows;
  // a duplicated code is listed where its original is (the node of its own
  // code), the copy is not.
  CeilingMap truth_map() const;
  // One line per departure from the nominal grid a person should know of
  // ("marker (2, 5) missing", "node (4, 1) shows code (6, 3)", ...).
  std::vector<std::string> notes() const { return notes_; }

 private:
  LaidMarker& node(int i, int j) {
    return nodes_[static_cast<size_t>(j) * static_cast<size_t>(side_) + static_cast<size_t>(i)];
  }

  CeilingLayout layout_;
  int side_ = 0;
  std::vector<LaidMarker> nodes_;
  std::vector<std::string> notes_;
};

}  // namespace ceilpose::sim
