#include "positioning_support.h"

#include <cmath>
#include <random>

namespace ceilpose::testing {

Pose2D pose_after(const SyntheticView& view, const Pose2D& robot, double tau_s) {
  const double w = view.yaw_rate_radps, turn = w * tau_s;
  // ∫ R(yaw + w·t)·v dt over [0, tau]: the body-frame step, then to the world.
  const double along = std::abs(turn) < 1e-12 ? tau_s : std::sin(turn) / w;
  const double across = std::abs(turn) < 1e-12 ? 0.0 : (1.0 - std::cos(turn)) / w;
  const double f = view.forward_mps * along - view.left_mps * across;
  const double l = view.left_mps * along + view.forward_mps * across;
  const double c = std::cos(robot.yaw_rad), s = std::sin(robot.yaw_rad);
  return {robot.x_m + c * f - s * l, robot.y_m + s * f + c * l, robot.yaw_rad + turn};
}

std::vector<MarkerObservation> observe(const SyntheticView& view, const Pose2D& robot) {
  const CeilingLayout& l = view.layout;
  const CameraPose pose = camera_pose_from_robot(robot, view.mount);
  const bool rolling = view.intrinsics.readout_ms > 0.0;
  std::mt19937_64 rng(view.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<MarkerObservation> out;
  const double half_e = l.rect_width_m, half_n = 0.5 * l.rect_height_m;
  for (int i = 0; i < l.codes(); ++i)
    for (int j = 0; j < l.codes(); ++j) {
      const Vec3 c = l.marker_centre_w(i, j);
      auto project = [&](double e, double n, double* u, double* v) {
        const Vec3 p{c[0] + e, c[1] + n, c[2]};
        if (!project_world_point(view.intrinsics, pose, p, u, v)) return false;
        // The row and the pose it was exposed at agree after a few rounds
        // (each round's row change shrinks by the view's motion over the
        // readout, a few percent of the frame).
        for (int round = 0; rolling && round < 8; ++round) {
          const Pose2D at = pose_after(view, robot, row_time_s(view.intrinsics, *v));
          if (!project_world_point(view.intrinsics, camera_pose_from_robot(at, view.mount), p, u,
                                   v))
            return false;
        }
        return true;
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
