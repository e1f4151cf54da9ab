#include "positioning_support.h"

#include <cmath>
#include <random>

namespace ceilpose::testing {

std::vector<MarkerObservation> observe(const SyntheticView& view, const Pose2D& robot) {
  const CeilingLayout& l = view.layout;
  const CameraPose pose = camera_pose_from_robot(robot, view.mount);
  std::mt19937_64 rng(view.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<MarkerObservation> out;
  const double half_e = l.rect_width_m, half_n = 0.5 * l.rect_height_m;
  for (int i = 0; i < l.codes(); ++i)
    for (int j = 0; j < l.codes(); ++j) {
      const Vec3 c = l.marker_centre_w(i, j);
      auto project = [&](double e, double n, double* u, double* v) {
        return project_world_point(view.intrinsics, pose, {c[0] + e, c[1] + n, c[2]}, u, v);
      };
      auto inside = [&](double u, double v) {
        return u >= 0.0 && v >= 0.0 && u <= view.intrinsics.width - 1.0 &&
               v <= view.intrinsics.height - 1.0;
      };
      MarkerObservation m;
      m.code_i = i;
      m.code_j = j;
      bool whole = true, any = false;
      auto add = [&](double e, double n) {
        double u = 0, v = 0;
        if (!project(e, n, &u, &v)) {
          whole = false;
          return;
        }
        if (!inside(u, v)) {
          whole = false;
          return;
        }
        any = true;
        if (m.point_count >= kMaxPointsPerMarker) return;
        m.points[m.point_count++] = {e, n, u + view.noise_px * noise(rng),
                                     v + view.noise_px * noise(rng)};
      };
      // Corners of both rectangles, then the dot centres of set bits.
      for (double e : {-half_e, 0.0, half_e})
        for (double n : {-half_n, half_n}) add(e, n);
      for (int k = 0; k < l.bits; ++k) {
        if (l.slot_bit(i, k)) add(l.red_centre_e_m(), l.slot_n_m(k));
        if (l.slot_bit(j, k)) add(l.green_centre_e_m(), l.slot_n_m(k));
      }
      if (!any || (!whole && !view.include_partial)) continue;
      m.whole = whole;
      double u = 0, v = 0;
      project(0.0, 0.0, &u, &v);
      m.centre_u_px = u + view.noise_px * noise(rng);
      m.centre_v_px = v + view.noise_px * noise(rng);
      project(l.red_centre_e_m(), 0.0, &u, &v);
      m.red_u_px = u + view.noise_px * noise(rng);
      m.red_v_px = v + view.noise_px * noise(rng);
      project(l.green_centre_e_m(), 0.0, &u, &v);
      m.green_u_px = u + view.noise_px * noise(rng);
      m.green_v_px = v + view.noise_px * noise(rng);
      m.west_image_rad = std::atan2(m.green_v_px - m.red_v_px, m.green_u_px - m.red_u_px);
      out.push_back(m);
    }
  return out;
}

std::vector<MarkerFix> fixes_of(const ViewGeometry& view,
                                const std::vector<MarkerObservation>& markers) {
  std::vector<MarkerFix> fixes;
  for (size_t k = 0; k < markers.size(); ++k) {
    MarkerFix f;
    if (marker_fix(view, markers[k], static_cast<int>(k), {}, &f)) fixes.push_back(f);
  }
  return fixes;
}

}  // namespace ceilpose::testing
