#include "pipeline/marker_tracking.h"

#include <algorithm>
#include <cmath>

#include "core/camera_model.h"
#include "core/length_2d.h"
#include "pipeline/camera_motion.h"
#include "pipeline/rectangle_ends.h"

namespace ceilpose {

const char* to_string(FullSweepReason reason) {
  switch (reason) {
    case FullSweepReason::kNone:
      return "tracked";
    case FullSweepReason::kOff:
      return "off";
    case FullSweepReason::kNoFix:
      return "no_fix";
    case FullSweepReason::kScheduled:
      return "scheduled";
    case FullSweepReason::kUncertain:
      return "uncertain";
    case FullSweepReason::kTooMany:
      return "too_many";
    case FullSweepReason::kTrackFailed:
      return "track_failed";
  }
  return "unknown";
}

void PredictionErrors::add(double position_m, double yaw_rad) {
  if (++samples_ <= kSkipped) return;
  position_m_ = std::abs(position_m);
  yaw_rad_ = std::abs(yaw_rad);
}

namespace {

// The affine view of marker `p`'s frame (pixels per metre East and North at
// its centre, over 1 cm) seen from the robot's pose `s` advanced by tau_s
// along its arc, the camera on `mount`; false when a point does not project.
bool marker_frame_at(const ViewGeometry& view, const CameraMount& mount, const MarkerPlacement& p,
                     const MotionState& s, double tau_s, MarkerFrame* out) {
  constexpr double kStep_m = 0.01;
  double arc_x_m = 0.0, arc_y_m = 0.0;
  arc_displacement(s.x[3], s.x[4], s.x[5], tau_s, &arc_x_m, &arc_y_m);
  const Pose2D robot{s.x[0] + arc_x_m, s.x[1] + arc_y_m, s.x[2] + s.x[5] * tau_s};
  const CameraPose camera = camera_pose_from_robot(robot, mount);
  const double points_m[3][2] = {{0.0, 0.0}, {kStep_m, 0.0}, {0.0, kStep_m}};
  double u[3], v[3];
  const MarkerPlacement::Rotation rotation = p.rotation();
  for (int q = 0; q < 3; ++q) {
    double x_m = 0.0, y_m = 0.0;
    p.world_point(rotation, points_m[q][0], points_m[q][1], &x_m, &y_m);
    if (!project_world_point(view.intrinsics(), camera, {x_m, y_m, view.layout().height_m}, &u[q],
                             &v[q]))
      return false;
  }
  out->centre_u_px = u[0];
  out->centre_v_px = v[0];
  out->east_u = (u[1] - u[0]) / kStep_m;
  out->east_v = (v[1] - v[0]) / kStep_m;
  out->north_u = (u[2] - u[0]) / kStep_m;
  out->north_v = (v[2] - v[0]) / kStep_m;
  // West is image direction −East.
  out->west_image_rad = std::atan2(-out->east_v, -out->east_u);
  return std::isfinite(out->centre_u_px + out->centre_v_px + out->east_u + out->east_v +
                       out->north_u + out->north_v);
}

}  // namespace

double prediction_error_px(const ViewGeometry& view, const PredictionErrors& errors) {
  const CameraIntrinsics& k = view.intrinsics();
  const double px_per_m = std::max(k.fx, k.fy) / view.depth_m();
  const double half_diagonal_px = 0.5 * std::hypot(k.width, k.height);
  return errors.position_m() * px_per_m + errors.yaw_rad() * half_diagonal_px;
}

FullSweepReason plan_tracking(const ViewGeometry& view, const CameraMount& mount,
                              const DetectorParams& params, PositioningMode mode,
                              const MotionState& s, const PredictionErrors& errors,
                              TrackingPlan* plan) {
  const CameraIntrinsics& k = view.intrinsics();
  const CeilingLayout& layout = view.layout();
  const Pose2D robot{s.x[0], s.x[1], s.x[2]};
  const CameraPose camera = camera_pose_from_robot(robot, mount);
  const double px_per_m = std::max(k.fx, k.fy) / view.depth_m();
  // The margin: a fixed part (blur, edge quantisation, the model's own
  // error), the recent predictions' largest errors in position and, at the
  // frame's corners, in yaw, and how far the view moves during the readout
  // (the prediction is the centre row's).
  const double half_diagonal_px = 0.5 * std::hypot(k.width, k.height);
  // The view's speed, pixels a second: translation, and the yaw's rotation
  // at the frame's corners; how far it moves during half the readout.
  const double readout_s = std::max(0.0, k.readout_ms) * 1e-3;
  const double view_px_per_s =
      std::hypot(s.x[3], s.x[4]) * px_per_m + std::abs(s.x[5]) * half_diagonal_px;
  const double readout_px = view_px_per_s * 0.5 * readout_s;
  const double predictions_px = params.track_margin_errors * prediction_error_px(view, errors);
  const double margin_px = params.track_margin_px + predictions_px + readout_px;
  plan->margin_px = margin_px;
  plan->edges = params.track_edges && !positions_from_centroids(mode);
  plan->window_count = 0;
  plan->expected_whole = 0;
  plan->predicted_count = 0;
  if (!errors.known()) return FullSweepReason::kNoFix;
  if (!std::isfinite(margin_px)) return FullSweepReason::kUncertain;

  // Markers farther from the optical centre than the frame's half diagonal
  // on the ceiling, plus a marker and the margin, cannot be in view.
  const double marker_radius_m = std::hypot(layout.rect_width_m, 0.5 * layout.rect_height_m);
  const double reach_m = (half_diagonal_px + margin_px) / px_per_m + marker_radius_m;
  const double tilt_reach_m =
      view.depth_m() * std::tan(std::hypot(mount.tilt_x_rad, mount.tilt_y_rad));
  const double reach2_m2 = (reach_m + tilt_reach_m) * (reach_m + tilt_reach_m);
  const CeilingMap& map = view.map();
  const int codes = map.codes();
  int64_t area_px = 0;
  for (int j = 0; j < codes; ++j) {
    for (int i = 0; i < codes; ++i) {
      const MarkerPlacement* p = map.find(i, j);
      if (p == nullptr) continue;
      const double dx = p->x_m - camera.t_w[0], dy = p->y_m - camera.t_w[1];
      if (dx * dx + dy * dy > reach2_m2) continue;
      // The outline's corners, in order around it.
      constexpr double kCornerE[4] = {-1.0, 1.0, 1.0, -1.0}, kCornerN[4] = {-1.0, -1.0, 1.0, 1.0};
      std::array<double, 4> cu{}, cv{};
      bool projected = true;
      const MarkerPlacement::Rotation rotation = p->rotation();
      for (int c = 0; c < 4; ++c) {
        double x_m = 0.0, y_m = 0.0;
        p->world_point(rotation, kCornerE[c] * layout.rect_width_m,
                       kCornerN[c] * 0.5 * layout.rect_height_m, &x_m, &y_m);
        projected = projected &&
                    project_world_point(k, camera, {x_m, y_m, layout.height_m}, &cu[c], &cv[c]);
      }
      const double u_min = *std::min_element(cu.begin(), cu.end());
      const double u_max = *std::max_element(cu.begin(), cu.end());
      const double v_min = *std::min_element(cv.begin(), cv.end());
      const double v_max = *std::max_element(cv.begin(), cv.end());
      if (!projected || !std::isfinite(u_min + u_max + v_min + v_max)) {
        return FullSweepReason::kUncertain;
      }
      // Under lens distortion the outline's sides are curves: each window
      // widens by how far its sides' midpoints bow from the straight chords.
      double bow_px = 0.0;
      if (k.has_distortion()) {
        for (int c = 0; c < 4 && projected; ++c) {
          const int d = (c + 1) % 4;
          double x_m = 0.0, y_m = 0.0, u = 0.0, v = 0.0;
          p->world_point(rotation, 0.5 * (kCornerE[c] + kCornerE[d]) * layout.rect_width_m,
                         0.25 * (kCornerN[c] + kCornerN[d]) * layout.rect_height_m, &x_m, &y_m);
          projected = project_world_point(k, camera, {x_m, y_m, layout.height_m}, &u, &v);
          bow_px =
              std::max(bow_px, length_2d(u - 0.5 * (cu[c] + cu[d]), v - 0.5 * (cv[c] + cv[d])));
        }
        if (!projected || !std::isfinite(bow_px)) return FullSweepReason::kUncertain;
      }
      const double grow_px = margin_px + bow_px;
      const double x0 = u_min - grow_px, x1 = u_max + grow_px;
      const double y0 = v_min - grow_px, y1 = v_max + grow_px;
      // A marker cut by the frame's edge even if the prediction is off by
      // the whole margin cannot be decoded (pipeline: kCut): no window.
      const double w = k.width - 1.0, h = k.height - 1.0;
      if (u_min + margin_px < 0.0 || v_min + margin_px < 0.0 || u_max - margin_px > w ||
          v_max - margin_px > h) {
        continue;
      }
      if (plan->window_count == kMaxMarkersPerFrame) return FullSweepReason::kTooMany;
      PixelWindow& win = plan->windows[plan->window_count++];
      win.x0 = static_cast<int>(std::max(0.0, std::floor(x0)));
      win.y0 = static_cast<int>(std::max(0.0, std::floor(y0)));
      win.x1 = static_cast<int>(std::min(w, std::ceil(x1)));
      win.y1 = static_cast<int>(std::min(h, std::ceil(y1)));
      // The outline widened by the margin on every side: each corner moves
      // out along both of its sides' directions.
      const double eu = cu[1] - cu[0], ev = cv[1] - cv[0], nu = cu[3] - cu[0], nv = cv[3] - cv[0];
      const double e_len = length_2d(eu, ev), n_len = length_2d(nu, nv);
      if (e_len > 1.0 && n_len > 1.0) {
        win.quad = true;
        for (int c = 0; c < 4; ++c) {
          win.qu[c] = static_cast<float>(
              cu[c] + grow_px * (kCornerE[c] * eu / e_len + kCornerN[c] * nu / n_len));
          win.qv[c] = static_cast<float>(
              cv[c] + grow_px * (kCornerE[c] * ev / e_len + kCornerN[c] * nv / n_len));
        }
      }
      // Whole beyond doubt: inside the frame even if the prediction is off
      // by the whole margin.
      if (x0 >= 0.0 && y0 >= 0.0 && x1 <= w && y1 <= h) {
        if (plan->edges) {
          // Its frame where its centre row is exposed (the prediction is the
          // centre row's): two passes find the row.
          PredictedMarker& pm = plan->predicted[static_cast<size_t>(plan->predicted_count)];
          pm.code_i = i;
          pm.code_j = j;
          bool framed = marker_frame_at(view, mount, *p, s, 0.0, &pm.frame);
          if (framed && k.readout_ms > 0.0)
            framed =
                marker_frame_at(view, mount, *p, s, row_time_s(k, pm.frame.centre_v_px), &pm.frame);
          if (!framed) return FullSweepReason::kUncertain;
          ++plan->predicted_count;
        }
        plan->whole[plan->expected_whole++] = j * codes + i;
      }
    }
  }
  if (plan->edges) {
    // Edge-tracked frames sweep no window, so the windows' area does not
    // matter: the profiles across each predicted edge must cross it, which
    // they do while the prediction's likely error stays within a
    // profile's half-length. A marker found off its prediction is measured
    // again where it is, or refused (pipeline). Each marker is predicted
    // where its own centre row is exposed, so of the readout only the
    // motion within the marker's rows is unpredicted, not the half frame's
    // a window allows for.
    const double marker_half_rows_px = marker_radius_m * px_per_m;
    const double error_px =
        predictions_px + view_px_per_s * readout_s * marker_half_rows_px / k.height;
    return error_px <= kEdgeProfileHalf_m * px_per_m ? FullSweepReason::kNone
                                                     : FullSweepReason::kUncertain;
  }
  plan->window_count = merge_windows(plan->windows, plan->window_count);
  for (const PixelWindow& w : plan->span()) area_px += w.area_px();  // boxes: an upper bound
  if (static_cast<double>(area_px) >
      params.track_max_area_share * static_cast<double>(k.width) * k.height) {
    return FullSweepReason::kUncertain;
  }
  return FullSweepReason::kNone;
}

}  // namespace ceilpose
