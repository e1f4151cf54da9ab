#pragma once
// Where every marker of the ceiling really is (SPEC §8): its centre, its
// rotation from the nominal orientation and their 1-sigma uncertainties. The
// nominal grid of SPEC §1 is the map whose markers all sit exactly at
// (i·g, j·g) with no rotation and no uncertainty. Positioning reads it on
// every frame; it is built once per configuration.
#include <cmath>
#include <vector>

#include "core/ceiling_layout.h"
#include "core/pose.h"

namespace ceilpose {

struct MarkerPlacement {
  bool present = false;  // the marker is on the ceiling (a map lists it)
  double x_m = 0.0;      // centre in `map`
  double y_m = 0.0;
  double yaw_rad = 0.0;  // rotation about the vertical from nominal, CCW
  double sigma_m = 0.0;  // 1-sigma of the centre, isotropic
  double sigma_yaw_rad = 0.0;
  int observations = 0;  // frames in which the survey decoded it (0: not known)

  // yaw_rad's cosine and sine, for world_point over many points of one
  // marker (a sine and a cosine each cost more than the point).
  struct Rotation {
    double cos = 1.0, sin = 0.0;
  };
  Rotation rotation() const { return {std::cos(yaw_rad), std::sin(yaw_rad)}; }

  // World (x, y) of the marker-frame point (e, n) (SPEC §2 frame, rotated by
  // yaw_rad about the centre); `r` is rotation().
  void world_point(const Rotation& r, double e_m, double n_m, double* x_m_out,
                   double* y_m_out) const {
    *x_m_out = x_m + r.cos * e_m - r.sin * n_m;
    *y_m_out = y_m + r.sin * e_m + r.cos * n_m;
  }
  void world_point(double e_m, double n_m, double* x_m_out, double* y_m_out) const {
    world_point(rotation(), e_m, n_m, x_m_out, y_m_out);
  }
  bool operator==(const MarkerPlacement&) const = default;
};

class CeilingMap {
 public:
  // The nominal grid of `layout`: every code present at (i·g, j·g).
  explicit CeilingMap(const CeilingLayout& layout) : bits_(layout.bits) {
    const int n = layout.codes();
    placements_.resize(static_cast<size_t>(n) * static_cast<size_t>(n));
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        MarkerPlacement& p = at(i, j);
        p.present = true;
        p.x_m = i * layout.grid_m;
        p.y_m = j * layout.grid_m;
      }
  }

  // A map in which no marker is present yet (a reader fills it with set()).
  static CeilingMap empty(const CeilingLayout& layout) {
    CeilingMap map(layout);
    for (MarkerPlacement& p : map.placements_) p = MarkerPlacement{};
    map.surveyed_ = true;
    return map;
  }

  int codes() const { return 1 << bits_; }
  bool valid_code(int i, int j) const { return i >= 0 && j >= 0 && i < codes() && j < codes(); }
  // nullptr when the code is outside the layout or the marker is not on the
  // ceiling.
  const MarkerPlacement* find(int i, int j) const {
    if (!valid_code(i, j)) return nullptr;
    const MarkerPlacement& p = placements_[index(i, j)];
    return p.present ? &p : nullptr;
  }
  void set(int i, int j, const MarkerPlacement& placement) { at(i, j) = placement; }
  MarkerPlacement* find_mutable(int i, int j) {
    return valid_code(i, j) && at(i, j).present ? &at(i, j) : nullptr;
  }
  // True for a map read from a survey, false for the nominal grid.
  bool surveyed() const { return surveyed_; }
  bool operator==(const CeilingMap&) const = default;
  int present_count() const {
    int n = 0;
    for (const MarkerPlacement& p : placements_) n += p.present ? 1 : 0;
    return n;
  }

 private:
  size_t index(int i, int j) const {
    return static_cast<size_t>(j) * static_cast<size_t>(codes()) + static_cast<size_t>(i);
  }
  MarkerPlacement& at(int i, int j) { return placements_[index(i, j)]; }

  int bits_ = 3;
  bool surveyed_ = false;
  std::vector<MarkerPlacement> placements_;
};

// A rigid motion of the ceiling plane: p -> R(rotation_rad)·p + (tx_m, ty_m).
struct PlaneMotion {
  double rotation_rad = 0.0;
  double tx_m = 0.0;
  double ty_m = 0.0;
  void apply(double* x_m, double* y_m) const {
    const double c = std::cos(rotation_rad), s = std::sin(rotation_rad);
    const double x = *x_m, y = *y_m;
    *x_m = c * x - s * y + tx_m;
    *y_m = s * x + c * y + ty_m;
  }
};

// SPEC §8's datum: the rigid motion that best fits (least squares) the
// present markers' centres onto their nominal places (i·g, j·g). A map is in
// the datum when this is the identity.
PlaneMotion datum_motion(const CeilingMap& map, const CeilingLayout& layout);
// Moves every present marker of `map` by `motion` (centres and rotations).
void move_map(const PlaneMotion& motion, CeilingMap* map);

}  // namespace ceilpose
