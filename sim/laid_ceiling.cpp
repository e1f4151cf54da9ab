#include "sim/laid_ceiling.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include "core/units.h"
#include "sim/ceiling_scene.h"

namespace ceilpose::sim {
namespace {

// Standard normal from two hashes (Box–Muller), portable across libraries.
double normal(uint64_t seed, uint64_t k) {
  const double u1 = (static_cast<double>(mix64(seed ^ (2 * k)) >> 11) + 0.5) * 0x1.0p-53;
  const double u2 = static_cast<double>(mix64(seed ^ (2 * k + 1)) >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

std::string code_text(int i, int j) {
  char text[32];
  std::snprintf(text, sizeof text, "(%d, %d)", i, j);
  return text;
}

}  // namespace

LaidCeiling::LaidCeiling(const CeilingLayout& layout) : layout_(layout), side_(layout.codes()) {
  nodes_.resize(static_cast<size_t>(side_) * static_cast<size_t>(side_));
  for (int j = 0; j < side_; ++j)
    for (int i = 0; i < side_; ++i)
      node(i, j) = {true, i, j, i * layout.grid_m, j * layout.grid_m, 0.0};
}

LaidCeiling LaidCeiling::hand_laid(const CeilingLayout& layout, const HandLaidOptions& o) {
  LaidCeiling c(layout);
  const uint64_t seed = mix64(o.seed ^ 0x6C61696443656Cull);
  const int n = c.side_ * c.side_;
  for (int k = 0; k < n; ++k) {
    LaidMarker& m = c.nodes_[static_cast<size_t>(k)];
    m.x_m += o.sigma_m * normal(seed, 3 * static_cast<uint64_t>(k));
    m.y_m += o.sigma_m * normal(seed, 3 * static_cast<uint64_t>(k) + 1);
    m.yaw_rad = o.sigma_yaw_rad * normal(seed, 3 * static_cast<uint64_t>(k) + 2);
  }
  // Distinct interior nodes for the outlier, the duplicate and the missing
  // ones, so each shows as itself in the survey.
  std::vector<int> used;
  auto pick = [&](uint64_t salt) {
    for (uint64_t t = 0;; ++t) {
      const int k = static_cast<int>(mix64(seed ^ (salt * 7919 + t)) % static_cast<uint64_t>(n));
      const int i = k % c.side_, j = k / c.side_;
      const bool interior = i > 0 && j > 0 && i < c.side_ - 1 && j < c.side_ - 1;
      bool taken = false;
      for (int u : used) taken = taken || u == k;
      if ((interior || c.side_ < 3) && !taken) {
        used.push_back(k);
        return k;
      }
    }
  };
  char line[160];
  if (o.outlier_m > 0.0) {
    const int k = pick(1);
    LaidMarker& m = c.nodes_[static_cast<size_t>(k)];
    const double dir =
        2.0 * std::numbers::pi * (static_cast<double>(mix64(seed ^ 77) >> 11) * 0x1.0p-53);
    m.x_m = (k % c.side_) * layout.grid_m + o.outlier_m * std::cos(dir);
    m.y_m = (k / c.side_) * layout.grid_m + o.outlier_m * std::sin(dir);
    std::snprintf(line, sizeof line, "marker %s glued %.0f mm off its spot",
                  code_text(m.code_i, m.code_j).c_str(), o.outlier_m * 1000.0);
    c.notes_.emplace_back(line);
  }
  for (int q = 0; q < o.missing; ++q) {
    LaidMarker& m = c.nodes_[static_cast<size_t>(pick(100 + static_cast<uint64_t>(q)))];
    m.present = false;
    std::snprintf(line, sizeof line, "marker %s missing", code_text(m.code_i, m.code_j).c_str());
    c.notes_.emplace_back(line);
  }
  if (o.duplicate) {
    LaidMarker& original = c.nodes_[static_cast<size_t>(pick(2))];
    LaidMarker& copy = c.nodes_[static_cast<size_t>(pick(3))];
    std::snprintf(line, sizeof line, "node %s shows code %s (printed twice)",
                  code_text(copy.code_i, copy.code_j).c_str(),
                  code_text(original.code_i, original.code_j).c_str());
    c.notes_.emplace_back(line);
    copy.code_i = original.code_i;
    copy.code_j = original.code_j;
  }
  // The world frame is the one the nominal grid realises (SPEC §8's datum):
  // the laid markers, taken together, sit where the grid says.
  const PlaneMotion datum = datum_motion(c.truth_map(), layout);
  for (LaidMarker& m : c.nodes_) {
    datum.apply(&m.x_m, &m.y_m);
    m.yaw_rad = wrap_angle_rad(m.yaw_rad + datum.rotation_rad);
  }
  return c;
}

Result<LaidCeiling> LaidCeiling::parse(const std::string& spec, const CeilingLayout& layout,
                                       uint64_t seed) {
  if (spec == "nominal") return LaidCeiling(layout);
  const std::string prefix = "hand-laid";
  if (spec.rfind(prefix, 0) != 0) {
    return make_error("ceiling '" + spec +
                      "': expected nominal or hand-laid[:SIGMA_MM[:SIGMA_DEG]]");
  }
  HandLaidOptions o;
  o.seed = seed;
  std::string rest = spec.substr(prefix.size());
  double values[2] = {o.sigma_m * 1000.0, o.sigma_yaw_rad * kDegPerRad};
  for (double& v : values) {
    if (rest.empty()) break;
    if (rest[0] != ':') return make_error("ceiling '" + spec + "': expected ':' after hand-laid");
    char* end = nullptr;
    v = std::strtod(rest.c_str() + 1, &end);
    if (end == rest.c_str() + 1 || !std::isfinite(v) || v < 0.0 || v > 1000.0)
      return make_error("ceiling '" + spec + "': expected a sigma in mm (and degrees) >= 0");
    rest = end;
  }
  if (!rest.empty()) return make_error("ceiling '" + spec + "': unexpected '" + rest + "'");
  o.sigma_m = values[0] / 1000.0;
  o.sigma_yaw_rad = values[1] * kRadPerDeg;
  return hand_laid(layout, o);
}

CeilingMap LaidCeiling::truth_map() const {
  CeilingMap map = CeilingMap::empty(layout_);
  for (int j = 0; j < side_; ++j)
    for (int i = 0; i < side_; ++i) {
      const LaidMarker& m = at(i, j);
      const bool original = m.code_i == i && m.code_j == j;
      if (!m.present || !original) continue;
      MarkerPlacement p;
      p.present = true;
      p.x_m = m.x_m;
      p.y_m = m.y_m;
      p.yaw_rad = m.yaw_rad;
      map.set(i, j, p);
    }
  return map;
}

}  // namespace ceilpose::sim
