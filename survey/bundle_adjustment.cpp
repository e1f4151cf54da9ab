#include "survey/bundle_adjustment.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numeric>

#include "core/units.h"
#include "pipeline/change_of_axes.h"

namespace ceilpose {
namespace {

// The reprojection of one marker point: marker-frame point (e, n) of the
// marker (centre x, y, rotation) seen by the camera at (x, y, yaw) on the
// floor, lens at the mount's height, tilted by the mount's nominal tilt
// plus the estimated increment, through the intrinsics (fx, fy, cx, cy,
// k1, k2, p1, p2, k3), the markers' points at `size` times their nominal
// distance from the centre. Residual: projected minus measured, pixels.
struct Reprojection {
  double e_m, n_m, u_px, v_px, depth_m, tilt_x0_rad, tilt_y0_rad;

  template <typename T>
  bool operator()(const T* camera, const T* marker, const T* tilt, const T* k, const T* size,
                  T* r) const {
    using std::cos;
    using std::sin;
    const T cm = cos(marker[2]), sm = sin(marker[2]);
    const T e = size[0] * e_m, n = size[0] * n_m;
    const T dx = marker[0] + cm * e - sm * n - camera[0];
    const T dy = marker[1] + sm * e + cm * n - camera[1];
    // The level camera (SPEC §3), then the tilt (core/camera_model.h).
    T lx, ly;
    world_to_level(T(cos(camera[2])), T(sin(camera[2])), dx, dy, &lx, &ly);
    T px, py, pz;
    level_to_tilted(T(tilt_x0_rad) + tilt[0], T(tilt_y0_rad) + tilt[1], lx, ly, T(depth_m), &px,
                    &py, &pz);
    if (pz <= T(1e-6)) return false;
    T xd, yd;
    plumb_bob(k + 4, px / pz, py / pz, &xd, &yd);
    r[0] = k[0] * xd + k[2] - u_px;
    r[1] = k[1] * yd + k[3] - v_px;
    return true;
  }
};

// The pull of a marker towards its nominal spot and orientation, in the
// reprojections' unit: sigmas times the image points' own noise
// (*pixel_sigma, px), so that prior and points weigh what they should.
struct NominalPrior {
  double x_m, y_m, yaw_rad, inv_sigma_m, inv_sigma_rad;
  const double* pixel_sigma;
  template <typename T>
  bool operator()(const T* marker, T* r) const {
    r[0] = (marker[0] - x_m) * (inv_sigma_m * *pixel_sigma);
    r[1] = (marker[1] - y_m) * (inv_sigma_m * *pixel_sigma);
    r[2] = (marker[2] - yaw_rad) * (inv_sigma_rad * *pixel_sigma);
    return true;
  }
};

// With a known map (`calibrate robot`): the principal point about the
// declared one and the tilt increment about zero, 1-sigma kPrincipalPointPx
// and kTiltRad, in the reprojections' unit as NominalPrior.
constexpr double kPrincipalPointPx = 30.0;
constexpr double kTiltRad = 0.035;  // 2°
struct CameraPriors {
  double cx_px, cy_px;
  const double* pixel_sigma;
  template <typename T>
  bool operator()(const T* k, const T* tilt, T* r) const {
    r[0] = (k[2] - cx_px) * (*pixel_sigma / kPrincipalPointPx);
    r[1] = (k[3] - cy_px) * (*pixel_sigma / kPrincipalPointPx);
    r[2] = tilt[0] * (*pixel_sigma / kTiltRad);
    r[3] = tilt[1] * (*pixel_sigma / kTiltRad);
    return true;
  }
};

// A surveyed map's sigmas below these would hold its markers harder than
// any survey knows them (and make the problem stiff).
constexpr double kMinMapSigmaM = 0.0001;
constexpr double kMinMapSigmaRad = 0.0002;

// A frame's pose stands, for a sighting of a marker far off its spot, when
// at least this many of its markers are at their spots, and more of them
// than are off.
constexpr int kMinMarkersAtSpot = 2;

struct Sighting {
  int frame;
  int marker;  // index into the frame's markers
  int code;    // j · codes + i
};

class Progress final : public ceres::IterationCallback {
 public:
  explicit Progress(const std::function<void(const std::string&)>& report) : report_(report) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (report_) {
      char line[160];
      std::snprintf(line, sizeof line, "iteration %d: cost %.4g, step %.3g, %.1f s", s.iteration,
                    s.cost, s.step_norm, s.cumulative_time_in_seconds);
      report_(line);
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const std::function<void(const std::string&)>& report_;
};

int find_root(std::vector<int>& parent, int a) {
  while (parent[a] != a) a = parent[a] = parent[parent[a]];
  return a;
}

int nearest_node(double along_m, const CeilingLayout& layout) {
  return static_cast<int>(std::lround(along_m / layout.grid_m));
}

// Where each whole marker of each frame says it is, from the frame's own
// pose: sightings near the marker's nominal spot are of it, sightings far
// from it near another node of another marker printed with the same code.
// A sighting far from its spot yet nearest the spot's own node is either the
// marker glued that far off, or a frame whose pose was off. Positioning's
// grid consistency (grid_tolerance_units = 0.3 of 0.61 m) refuses a marker
// more than 0.18 m off, so a frame whose other markers are at their spots
// had its pose from them and sees that marker where it is: it is mapped
// there (against a known map, which holds its places, it is left out: it
// has moved since). A frame that sees most of its markers far off had its
// pose off: such sightings are left out, and not reported as "printed
// twice" (3 frames near their own node did, session 14, and sent someone
// looking for a marker that is not there).
void sort_sightings(const PipelineConfig& config, const std::vector<SurveyFrame>& frames,
                    const SurveyOptions& options, std::vector<Sighting>* home,
                    SurveyReport* report) {
  const ViewGeometry view(config);
  const CeilingLayout& layout = config.layout;
  const int codes = layout.codes();
  struct Away {
    double x_sum = 0.0, y_sum = 0.0;
    int frames = 0;
  };
  std::map<std::array<int, 4>, Away> away;  // code i, j, nearest node i, j
  std::vector<Sighting> off_spot;           // one frame's, far off but by their own node
  for (int f = 0; f < static_cast<int>(frames.size()); ++f) {
    const SurveyFrame& frame = frames[static_cast<size_t>(f)];
    const CameraPose cam = camera_pose_from_robot(frame.robot, config.mount);
    const double yaw = frame.robot.yaw_rad + config.mount.yaw_rad;
    off_spot.clear();
    int at_spot = 0;
    for (int k = 0; k < static_cast<int>(frame.markers.size()); ++k) {
      const MarkerObservation& m = frame.markers[static_cast<size_t>(k)];
      if (!m.whole || m.code_i < 0 || m.code_j < 0 || m.code_i >= codes || m.code_j >= codes)
        continue;
      double xn = 0.0, yn = 0.0;
      view.level_normalized(m.centre_u_px, m.centre_v_px, &xn, &yn);
      double dx = 0.0, dy = 0.0;
      view.ceiling_offset(yaw, xn, yn, &dx, &dy);
      const double x = cam.t_w[0] + dx, y = cam.t_w[1] + dy;
      double home_x = m.code_i * layout.grid_m, home_y = m.code_j * layout.grid_m;
      if (options.known_map != nullptr) {
        const MarkerPlacement* p = options.known_map->find(m.code_i, m.code_j);
        if (p == nullptr) continue;  // a map lists what is on the ceiling (SPEC §8)
        home_x = p->x_m;
        home_y = p->y_m;
      }
      const Sighting sighting{f, k, m.code_j * codes + m.code_i};
      if (std::hypot(x - home_x, y - home_y) <= options.duplicate_distance_m) {
        home->push_back(sighting);
        ++at_spot;
        continue;
      }
      const int node_i = nearest_node(x, layout), node_j = nearest_node(y, layout);
      if (node_i == nearest_node(home_x, layout) && node_j == nearest_node(home_y, layout)) {
        off_spot.push_back(sighting);
        continue;
      }
      Away& a = away[{m.code_i, m.code_j, node_i, node_j}];
      a.x_sum += x;
      a.y_sum += y;
      ++a.frames;
    }
    // Against a known map (calibrate robot) its places are held: a marker
    // that far from its mapped place has moved since, and is left out.
    if (options.known_map == nullptr && at_spot >= kMinMarkersAtSpot &&
        at_spot > static_cast<int>(off_spot.size()))
      home->insert(home->end(), off_spot.begin(), off_spot.end());
  }
  for (const auto& [key, a] : away) {
    if (a.frames < options.min_frames) continue;  // a stray misreading, not a marker
    report->duplicates.push_back(
        {key[0], key[1], a.x_sum / a.frames, a.y_sum / a.frames, a.frames});
  }
}

// Frames per code among `home`; codes seen too rarely are dropped from it.
std::vector<int> keep_well_seen(const SurveyOptions& options, int codes,
                                std::vector<Sighting>* home, SurveyReport* report) {
  std::vector<int> frames_of(static_cast<size_t>(codes * codes), 0);
  for (const Sighting& s : *home) ++frames_of[static_cast<size_t>(s.code)];
  for (int code = 0; code < codes * codes; ++code) {
    const int n = frames_of[static_cast<size_t>(code)];
    if (n > 0 && n < options.min_frames)
      report->too_rarely_seen.push_back({{code % codes, code / codes}, n});
  }
  std::erase_if(*home, [&](const Sighting& s) {
    return frames_of[static_cast<size_t>(s.code)] < options.min_frames;
  });
  return frames_of;
}

// Parts of the ceiling that no frame links: markers seen in one frame are
// joined.
int count_groups(const std::vector<Sighting>& home, int codes) {
  std::vector<int> parent(static_cast<size_t>(codes * codes));
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<bool> used(parent.size(), false);
  int last_frame = -1, first_code = -1;
  for (const Sighting& s : home) {
    used[static_cast<size_t>(s.code)] = true;
    if (s.frame != last_frame) {
      last_frame = s.frame;
      first_code = s.code;
      continue;
    }
    parent[static_cast<size_t>(find_root(parent, s.code))] = find_root(parent, first_code);
  }
  int groups = 0;
  for (int code = 0; code < codes * codes; ++code)
    if (used[static_cast<size_t>(code)] && find_root(parent, code) == code) ++groups;
  return groups;
}

// Frames closer than this in position and yaw see the ceiling alike: one
// viewpoint.
constexpr double kViewpointM = 0.05;
constexpr double kViewpointRad = 5.0 * kRadPerDeg;

// Distinct viewpoints among the frames with a used sighting (greedy: a
// frame far from every viewpoint so far is a new one).
int count_viewpoints(const std::vector<SurveyFrame>& frames, const std::vector<Sighting>& home) {
  std::vector<bool> used(frames.size(), false);
  for (const Sighting& s : home) used[static_cast<size_t>(s.frame)] = true;
  std::vector<Pose2D> views;
  for (size_t f = 0; f < frames.size(); ++f) {
    if (!used[f]) continue;
    const Pose2D& p = frames[f].robot;
    bool seen = false;
    for (const Pose2D& v : views)
      if (std::hypot(p.x_m - v.x_m, p.y_m - v.y_m) < kViewpointM &&
          std::abs(wrap_angle_rad(p.yaw_rad - v.yaw_rad)) < kViewpointRad) {
        seen = true;
        break;
      }
    if (!seen) views.push_back(p);
  }
  return static_cast<int>(views.size());
}

double rms_px(ceres::Problem& problem, const std::vector<ceres::ResidualBlockId>& blocks) {
  ceres::Problem::EvaluateOptions eval;
  eval.residual_blocks = blocks;
  eval.apply_loss_function = false;
  std::vector<double> residuals;
  problem.Evaluate(eval, nullptr, &residuals, nullptr, nullptr);
  double sum = 0.0;
  for (double r : residuals) sum += r * r;
  return residuals.empty() ? 0.0 : std::sqrt(sum / (static_cast<double>(residuals.size()) / 2.0));
}

// Marker sigmas in the datum: the joint covariance of all mapped markers,
// with the rigid motion that the datum takes out projected away (without
// that, every marker would carry the uncertainty of where the whole ceiling
// sits, which the datum fixes by definition), scaled by the points' variance
// (every residual is in units of it).
Result<void> marker_sigmas(ceres::Problem& problem, const std::vector<int>& mapped,
                           std::vector<std::array<double, 3>>& markers, double variance_px2,
                           int threads, CeilingMap* map, int codes) {
  ceres::Covariance::Options cov_options;
  cov_options.algorithm_type = ceres::SPARSE_QR;
  cov_options.num_threads = threads;
  ceres::Covariance covariance(cov_options);
  std::vector<std::pair<const double*, const double*>> pairs;
  const int n = static_cast<int>(mapped.size());
  for (int a = 0; a < n; ++a)
    for (int b = a; b < n; ++b)
      pairs.emplace_back(markers[static_cast<size_t>(mapped[a])].data(),
                         markers[static_cast<size_t>(mapped[b])].data());
  if (!covariance.Compute(pairs, &problem))
    return make_error("the survey's covariance could not be computed (rank-deficient problem)");
  const int dim = 3 * n;
  std::vector<double> full(static_cast<size_t>(dim * dim));
  double block[9];
  for (int a = 0; a < n; ++a)
    for (int b = a; b < n; ++b) {
      covariance.GetCovarianceBlock(markers[static_cast<size_t>(mapped[a])].data(),
                                    markers[static_cast<size_t>(mapped[b])].data(), block);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
          full[static_cast<size_t>((3 * a + r) * dim + 3 * b + c)] = block[r * 3 + c];
          full[static_cast<size_t>((3 * b + c) * dim + 3 * a + r)] = block[r * 3 + c];
        }
    }
  // The datum's linearised correction: δ'_k = δ_k − (δt + δφ × (p_k − p̄)),
  // δθ'_k = δθ_k − δφ, with δt the mean shift and δφ the best-fit turn.
  double px = 0.0, py = 0.0;
  for (int k : mapped) {
    px += markers[static_cast<size_t>(k)][0] / n;
    py += markers[static_cast<size_t>(k)][1] / n;
  }
  double spread = 0.0;
  for (int k : mapped) {
    spread += std::pow(markers[static_cast<size_t>(k)][0] - px, 2) +
              std::pow(markers[static_cast<size_t>(k)][1] - py, 2);
  }
  std::vector<double> p(static_cast<size_t>(dim * dim), 0.0);
  for (int a = 0; a < n; ++a) {
    const double ax = markers[static_cast<size_t>(mapped[a])][0] - px;
    const double ay = markers[static_cast<size_t>(mapped[a])][1] - py;
    for (int b = 0; b < n; ++b) {
      const double bx = markers[static_cast<size_t>(mapped[b])][0] - px;
      const double by = markers[static_cast<size_t>(mapped[b])][1] - py;
      // δφ = Σ_b (b × δ_b) / spread: its row over δ_b is (−by, bx)/spread.
      const double phi_x = spread > 0.0 ? -by / spread : 0.0;
      const double phi_y = spread > 0.0 ? bx / spread : 0.0;
      auto at = [&](int r, int c) -> double& { return p[static_cast<size_t>(r * dim + c)]; };
      // x'_a = x_a − δt_x + δφ·ay ; y'_a = y_a − δt_y − δφ·ax
      at(3 * a, 3 * b) -= 1.0 / n - phi_x * ay;
      at(3 * a, 3 * b + 1) -= phi_y * -ay;
      at(3 * a + 1, 3 * b) -= phi_x * ax;
      at(3 * a + 1, 3 * b + 1) -= 1.0 / n + phi_y * ax;
      at(3 * a + 2, 3 * b) -= phi_x;
      at(3 * a + 2, 3 * b + 1) -= phi_y;
    }
    for (int r = 0; r < 3; ++r) p[static_cast<size_t>((3 * a + r) * dim + 3 * a + r)] += 1.0;
  }
  for (int a = 0; a < n; ++a) {
    double var[3] = {0.0, 0.0, 0.0};
    for (int r = 0; r < 3; ++r) {
      const size_t row = static_cast<size_t>((3 * a + r) * dim);
      for (int i = 0; i < dim; ++i) {
        if (p[row + static_cast<size_t>(i)] == 0.0) continue;
        double s = 0.0;
        for (int j = 0; j < dim; ++j)
          s += full[static_cast<size_t>(i * dim + j)] * p[row + static_cast<size_t>(j)];
        var[r] += p[row + static_cast<size_t>(i)] * s;
      }
    }
    MarkerPlacement* placement = map->find_mutable(mapped[a] % codes, mapped[a] / codes);
    placement->sigma_m = std::sqrt(std::max(0.0, variance_px2 * 0.5 * (var[0] + var[1])));
    placement->sigma_yaw_rad = std::sqrt(std::max(0.0, variance_px2 * var[2]));
  }
  return {};
}

// The covariance above treats every image point as independent, but the
// points of one sighting share its frame's pose and the detector's biases
// for that view, so it claims too much (on the simulator, 3x smaller sigmas
// than the true errors). What the sightings themselves say is the honest
// floor: each sighting's residuals ask for a shift of the marker; the
// scatter of those shifts over the marker's N sightings, over sqrt(N), is
// how well its centre (and rotation) is known.
void scatter_sigmas(ceres::Problem& problem, const std::vector<ceres::ResidualBlockId>& blocks,
                    const std::vector<int>& sighting_of, const std::vector<Sighting>& home,
                    int codes, CeilingMap* map) {
  struct Normal3 {
    double jtj[9] = {};
    double jtr[3] = {};
  };
  std::vector<Normal3> per_sighting(home.size());
  // Only the marker's Jacobian: Ceres refuses one for a constant block.
  double r[2], jm[6];
  double* jacobians[5] = {nullptr, jm, nullptr, nullptr, nullptr};
  for (size_t b = 0; b < blocks.size(); ++b) {
    double cost = 0.0;
    if (!problem.EvaluateResidualBlock(blocks[b], false, &cost, r, jacobians)) continue;
    Normal3& n = per_sighting[static_cast<size_t>(sighting_of[b])];
    for (int i = 0; i < 3; ++i) {
      n.jtr[i] += jm[i] * r[0] + jm[3 + i] * r[1];
      for (int j = 0; j < 3; ++j) n.jtj[i * 3 + j] += jm[i] * jm[j] + jm[3 + i] * jm[3 + j];
    }
  }
  struct Spread {
    double sum[3] = {}, sum2[3] = {};
    int n = 0;
  };
  std::vector<Spread> spread(static_cast<size_t>(codes * codes));
  for (size_t h = 0; h < home.size(); ++h) {
    const Normal3& n = per_sighting[h];
    // Solve the 3x3 system by Cramer's rule (it is tiny and well posed).
    const double* a = n.jtj;
    const double det = a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
                       a[2] * (a[3] * a[7] - a[4] * a[6]);
    if (!(std::abs(det) > 0.0)) continue;
    double x[3];
    for (int c = 0; c < 3; ++c) {
      double m[9];
      std::copy(a, a + 9, m);
      for (int row = 0; row < 3; ++row) m[row * 3 + c] = n.jtr[row];
      x[c] = (m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
              m[2] * (m[3] * m[7] - m[4] * m[6])) /
             det;
    }
    Spread& sp = spread[static_cast<size_t>(home[h].code)];
    for (int c = 0; c < 3; ++c) {
      sp.sum[c] += x[c];
      sp.sum2[c] += x[c] * x[c];
    }
    ++sp.n;
  }
  for (int code = 0; code < codes * codes; ++code) {
    const Spread& sp = spread[static_cast<size_t>(code)];
    MarkerPlacement* p = map->find_mutable(code % codes, code / codes);
    if (p == nullptr || sp.n < 2) continue;
    double var[3];
    for (int c = 0; c < 3; ++c)
      var[c] = std::max(0.0, (sp.sum2[c] - sp.sum[c] * sp.sum[c] / sp.n) / (sp.n - 1)) / sp.n;
    p->sigma_m = std::max(p->sigma_m, std::sqrt(0.5 * (var[0] + var[1])));
    p->sigma_yaw_rad = std::max(p->sigma_yaw_rad, std::sqrt(var[2]));
  }
}

// With a known map: the 1-sigma of fx, fy, k1, k2 and the tilt (points'
// variance `variance_px2`). Their covariance over every image point; the
// points of one view share its pose, so these are lower bounds.
Result<SurveyReport> camera_sigmas(ceres::Problem& problem, const double* intrinsics,
                                   const double* tilt, bool intrinsics_free, double variance_px2,
                                   int threads, SurveyReport report) {
  ceres::Covariance::Options cov_options;
  cov_options.algorithm_type = ceres::SPARSE_QR;
  cov_options.num_threads = threads;
  ceres::Covariance covariance(cov_options);
  std::vector<std::pair<const double*, const double*>> pairs{{tilt, tilt}};
  if (intrinsics_free) pairs.emplace_back(intrinsics, intrinsics);
  if (!covariance.Compute(pairs, &problem))
    return make_error(
        "the camera's covariance could not be computed: the drive does not determine the camera "
        "(rank-deficient problem)");
  double t[4];
  covariance.GetCovarianceBlock(tilt, tilt, t);
  report.sigma_tilt_rad = {std::sqrt(variance_px2 * t[0]), std::sqrt(variance_px2 * t[3])};
  if (intrinsics_free) {
    double k[81];
    covariance.GetCovarianceBlock(intrinsics, intrinsics, k);
    const int index[6] = {0, 1, 4, 5, 2, 3};  // fx, fy, k1, k2, cx, cy
    for (int i = 0; i < 6; ++i)
      report.sigma_intrinsics[static_cast<size_t>(i)] =
          std::sqrt(variance_px2 * std::max(0.0, k[index[i] * 9 + index[i]]));
  }
  return report;
}

}  // namespace

Result<SurveyReport> survey_ceiling(const PipelineConfig& config,
                                    const std::vector<SurveyFrame>& frames,
                                    const SurveyOptions& options) {
  const CeilingLayout& layout = config.layout;
  const int codes = layout.codes();
  SurveyReport report(layout, config.intrinsics);
  std::vector<Sighting> home;
  sort_sightings(config, frames, options, &home, &report);
  const std::vector<int> frames_of = keep_well_seen(options, codes, &home, &report);
  if (home.empty()) {
    return make_error("no marker was decoded in " + std::to_string(options.min_frames) +
                      " or more of the " + std::to_string(frames.size()) +
                      " frames with a pose: walk under the ceiling with the camera looking up");
  }
  report.groups = count_groups(home, codes);
  report.viewpoints = count_viewpoints(frames, home);
  if (report.viewpoints < options.min_viewpoints) {
    char why[320];
    std::snprintf(why, sizeof why,
                  "the %zu frames saw the ceiling from %d place(s) (frames within %.0f mm and "
                  "%.0f deg of another count as one), %d needed: a survey of a robot that did "
                  "not move, or of one frame repeated, cannot tell the markers' places from the "
                  "camera's errors; walk under the ceiling",
                  frames.size(), report.viewpoints, 1000.0 * kViewpointM,
                  kViewpointRad * kDegPerRad, options.min_viewpoints);
    return make_error(why);
  }

  // Unknowns, at their starting values: the frames' own poses, the nominal
  // grid, the configured camera.
  std::vector<std::array<double, 3>> cameras(frames.size());
  for (size_t f = 0; f < frames.size(); ++f) {
    const CameraPose cam = camera_pose_from_robot(frames[f].robot, config.mount);
    cameras[f] = {cam.t_w[0], cam.t_w[1],
                  wrap_angle_rad(frames[f].robot.yaw_rad + config.mount.yaw_rad)};
  }
  // Each marker's starting place and the prior that holds it: its nominal
  // spot with the survey's sigmas, or its mapped place with the map's.
  std::vector<std::array<double, 3>> markers(static_cast<size_t>(codes * codes));
  std::vector<NominalPrior> priors(static_cast<size_t>(codes * codes));
  for (int code = 0; code < codes * codes; ++code) {
    NominalPrior& prior = priors[static_cast<size_t>(code)];
    prior = {(code % codes) * layout.grid_m, (code / codes) * layout.grid_m,    0.0,
             1.0 / options.prior_sigma_m,    1.0 / options.prior_sigma_yaw_rad, nullptr};
    if (options.known_map != nullptr) {
      if (const MarkerPlacement* p = options.known_map->find(code % codes, code / codes)) {
        prior = {p->x_m,
                 p->y_m,
                 p->yaw_rad,
                 1.0 / std::max(p->sigma_m, kMinMapSigmaM),
                 1.0 / std::max(p->sigma_yaw_rad, kMinMapSigmaRad),
                 nullptr};
      }
    }
    markers[static_cast<size_t>(code)] = {prior.x_m, prior.y_m, prior.yaw_rad};
  }
  std::array<double, 2> tilt{0.0, 0.0};
  // The markers' size as the detector sees it. Free, so that distances on
  // the ceiling are measured against the grid's spacing (the markers'
  // nominal spots, through their prior) and the camera's focal length, not
  // against the size of the markers: the detector's centroids put the red
  // and green centres 0.33 % too close together (0.1 px), and printers
  // scale by as much. Held at the printed size, the survey found fx 0.33 %
  // short with --intrinsics and put far markers 5-6 mm off.
  double marker_size = 1.0;
  const CameraIntrinsics& k0 = config.intrinsics;
  std::array<double, 9> intrinsics{k0.fx, k0.fy, k0.cx, k0.cy};
  std::copy(k0.distortion.begin(), k0.distortion.end(), intrinsics.begin() + 4);

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::HuberLoss huber(options.robust_px);
  std::vector<ceres::ResidualBlockId> reprojections;
  std::vector<int> sighting_of;  // per reprojection: index into home
  std::vector<bool> frame_used(frames.size(), false);
  const double depth_m = layout.height_m - config.mount.lens_height_m;
  for (size_t h = 0; h < home.size(); ++h) {
    const Sighting& s = home[h];
    const MarkerObservation& m =
        frames[static_cast<size_t>(s.frame)].markers[static_cast<size_t>(s.marker)];
    for (int p = 0; p < std::min(m.point_count, kMaxPointsPerMarker); ++p) {
      const MarkerPointObservation& pt = m.points[static_cast<size_t>(p)];
      // Edge points are measured across their edge only; the survey's
      // marker size and intrinsics were settled on the centroids, which
      // carry its scale (decisions.md, "Edge points").
      if (pt.is_edge()) continue;
      auto* cost = new ceres::AutoDiffCostFunction<Reprojection, 2, 3, 3, 2, 9, 1>(
          new Reprojection{pt.e_m, pt.n_m, pt.u_px, pt.v_px, depth_m, config.mount.tilt_x_rad,
                           config.mount.tilt_y_rad});
      reprojections.push_back(
          problem.AddResidualBlock(cost, &huber, cameras[static_cast<size_t>(s.frame)].data(),
                                   markers[static_cast<size_t>(s.code)].data(), tilt.data(),
                                   intrinsics.data(), &marker_size));
      sighting_of.push_back(static_cast<int>(h));
      ++report.points;
    }
    ++report.sightings;
    frame_used[static_cast<size_t>(s.frame)] = true;
  }
  std::vector<int> mapped;
  double pixel_sigma = options.first_pixel_sigma_px;
  for (int code = 0; code < codes * codes; ++code) {
    if (frames_of[static_cast<size_t>(code)] < options.min_frames) continue;
    mapped.push_back(code);
    NominalPrior prior = priors[static_cast<size_t>(code)];
    prior.pixel_sigma = &pixel_sigma;
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<NominalPrior, 3, 3>(new NominalPrior(prior)), nullptr,
        markers[static_cast<size_t>(code)].data());
  }
  report.frames_used = static_cast<int>(std::count(frame_used.begin(), frame_used.end(), true));
  // A level camera at a known height cannot tell a principal point (or a
  // decentring distortion, or a tilt) that is off from a camera mounted off
  // the robot's centre: each shifts the whole image alike, and every frame's
  // free position absorbs it (tried: cx came out 17 px off and poses 68 mm
  // off). So the survey estimates the focal lengths and the radial
  // distortion, and holds cx, cy, p1, p2 and k3 at the declared camera (a
  // checkerboard calibration measures them; `calibrate mount` the offset).
  //
  // With the markers held by a map, a strong radial distortion shows where
  // its centre (the principal point) is, and the tilt shows in the keystone
  // of the view; both are free, each held by a prior about the declared
  // camera (CameraPriors) so that a lens with little distortion leaves the
  // principal point where it was declared and the frames' positions (then
  // the mount offset) absorb it, as they would a tilt.
  if (options.estimate_intrinsics && options.known_map != nullptr) {
    const CameraIntrinsics& declared =
        options.declared_camera != nullptr ? *options.declared_camera : k0;
    problem.SetManifold(intrinsics.data(), new ceres::SubsetManifold(9, {6, 7, 8}));
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CameraPriors, 4, 9, 2>(
                                 new CameraPriors{declared.cx, declared.cy, &pixel_sigma}),
                             nullptr, intrinsics.data(), tilt.data());
  } else if (options.estimate_intrinsics) {
    problem.SetParameterBlockConstant(tilt.data());
    problem.SetManifold(intrinsics.data(), new ceres::SubsetManifold(9, {2, 3, 6, 7, 8}));
  } else {
    problem.SetParameterBlockConstant(intrinsics.data());
  }

  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::SPARSE_SCHUR;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (size_t f = 0; f < frames.size(); ++f)
    if (frame_used[f]) ordering->AddElementToGroup(cameras[f].data(), 0);
  for (int code : mapped) ordering->AddElementToGroup(markers[static_cast<size_t>(code)].data(), 1);
  ordering->AddElementToGroup(tilt.data(), 1);
  ordering->AddElementToGroup(intrinsics.data(), 1);
  ordering->AddElementToGroup(&marker_size, 1);
  solver.linear_solver_ordering = ordering;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = options.threads;
  solver.function_tolerance = 1e-10;
  solver.parameter_tolerance = 1e-10;
  Progress progress(options.progress);
  solver.callbacks.push_back(&progress);
  report.initial_rms_px = rms_px(problem, reprojections);
  const auto start = std::chrono::steady_clock::now();
  // Twice: the second time with the prior weighed against the noise the
  // points showed in the first (the covariance is then in the right units).
  for (int pass = 0; pass < 2; ++pass) {
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    if (!summary.IsSolutionUsable())
      return make_error("the bundle adjustment failed: " + summary.message);
    report.iterations += static_cast<int>(summary.iterations.size());
    report.rms_px = rms_px(problem, reprojections);
    pixel_sigma = std::max(report.rms_px, 0.01);
  }
  report.solve_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.cameras = cameras;
  report.used = frame_used;
  CameraIntrinsics& k = report.intrinsics;
  k.fx = intrinsics[0];
  k.fy = intrinsics[1];
  k.cx = intrinsics[2];
  k.cy = intrinsics[3];
  std::copy(intrinsics.begin() + 4, intrinsics.end(), k.distortion.begin());
  report.marker_size = marker_size;
  report.tilt_x_rad = config.mount.tilt_x_rad + tilt[0];
  report.tilt_y_rad = config.mount.tilt_y_rad + tilt[1];
  if (options.known_map != nullptr)
    return camera_sigmas(problem, intrinsics.data(), tilt.data(), options.estimate_intrinsics,
                         pixel_sigma * pixel_sigma, options.threads, std::move(report));

  for (int code : mapped) {
    const auto& m = markers[static_cast<size_t>(code)];
    MarkerPlacement p;
    p.present = true;
    p.x_m = m[0];
    p.y_m = m[1];
    p.yaw_rad = wrap_angle_rad(m[2]);
    p.observations = frames_of[static_cast<size_t>(code)];
    report.map.set(code % codes, code / codes, p);
  }
  const double variance_px2 = pixel_sigma * pixel_sigma;
  auto sigmas =
      marker_sigmas(problem, mapped, markers, variance_px2, options.threads, &report.map, codes);
  if (!sigmas) return sigmas.error();
  scatter_sigmas(problem, reprojections, sighting_of, home, codes, &report.map);
  move_map(datum_motion(report.map, layout), &report.map);

  for (int code : mapped) {
    const MarkerPlacement& p = *report.map.find(code % codes, code / codes);
    const double shift =
        std::hypot(p.x_m - (code % codes) * layout.grid_m, p.y_m - (code / codes) * layout.grid_m);
    if (shift > report.largest_shift_m) {
      report.largest_shift_m = shift;
      report.largest_shift_code = {code % codes, code / codes};
    }
    if (std::abs(p.yaw_rad) > report.largest_turn_rad) {
      report.largest_turn_rad = std::abs(p.yaw_rad);
      report.largest_turn_code = {code % codes, code / codes};
    }
  }
  return report;
}

}  // namespace ceilpose
