#pragma once
// The ceiling survey (SPEC §10): where every marker of a hand-laid ceiling
// really is, from one or more walks under it, by a bundle adjustment with
// Ceres over every frame. Unknowns: each frame's camera (position and yaw on
// the floor; the lens height is the mount's), each marker's centre and
// rotation, the camera's mounting tilt and, when asked, its intrinsics.
// Observations: every image point the detector measures on every decoded
// marker. A Huber loss keeps a mis-measured point from pulling the solution;
// a prior pulls each marker towards its nominal spot so that markers seen
// rarely stay sane; the result is put in SPEC §8's datum. Offline only.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/ceiling_map.h"
#include "core/pose.h"
#include "core/result.h"
#include "pipeline/marker_observation.h"
#include "pipeline/pipeline_config.h"

namespace ceilpose {

// One frame of a walk: its decoded whole markers and its own pose against
// the nominal grid (the starting value; frames without one are not used).
struct SurveyFrame {
  int64_t timestamp_ns = 0;
  Pose2D robot;
  std::vector<MarkerObservation> markers;
};

struct SurveyOptions {
  double prior_sigma_m = 0.05;          // marker centre about its nominal spot, 1-sigma
  double prior_sigma_yaw_rad = 0.0873;  // marker rotation about nominal, 1-sigma (5°)
  double robust_px = 1.0;               // Huber threshold on a point's residual, px
  // Image points' noise assumed for the first solve, px, weighing the
  // markers' priors against the points; the second solve uses the
  // residuals' own. Only the first solve's starting balance depends on it.
  double first_pixel_sigma_px = 0.25;
  int min_frames = 3;  // a marker is mapped when decoded in this many frames
  // Fewer distinct viewpoints than this (frames within 50 mm and 5° are one)
  // cannot separate the markers' places from the camera's errors: refused.
  int min_viewpoints = 5;
  // A sighting farther than this from the marker's nominal spot is of
  // another marker printed with the same code.
  double duplicate_distance_m = 0.2;
  bool estimate_intrinsics = false;  // fx, fy, k1, k2 (cx, cy, p1, p2, k3 held: see .cpp)
  // A surveyed ceiling (`calibrate robot`): its markers start at their mapped
  // places and are held there by priors of their own sigmas, codes it does
  // not list are not used, the tilt and the principal point are estimated
  // with the intrinsics (priors about the declared camera), and no map is
  // made (the report's map stays empty).
  const CeilingMap* known_map = nullptr;
  // The camera whose principal point the known_map priors hold to (null: the
  // configuration's). Decoding again with a camera found, the prior stays
  // about the declared one rather than following each pass.
  const CameraIntrinsics* declared_camera = nullptr;
  int max_iterations = 100;
  int threads = 1;
  // Called once per solver iteration with a one-line progress message.
  std::function<void(const std::string&)> progress;
};

// A code seen away from its own place: a second marker printed with it.
struct SurveyDuplicate {
  int code_i = 0, code_j = 0;
  double x_m = 0.0, y_m = 0.0;  // where the other one is (mean sighting)
  int frames = 0;
};

struct SurveyReport {
  SurveyReport(const CeilingLayout& layout, const CameraIntrinsics& camera)
      : map(CeilingMap::empty(layout)), intrinsics(camera) {}
  CeilingMap map;               // SPEC §8, in the datum
  CameraIntrinsics intrinsics;  // estimated when asked, else the input camera
  int frames_used = 0;
  int sightings = 0;  // marker observations used
  int points = 0;     // image points used
  int iterations = 0;
  double solve_s = 0.0;
  double initial_rms_px = 0.0;
  double rms_px = 0.0;
  int groups = 0;      // parts of the ceiling no frame links to the others
  int viewpoints = 0;  // distinct places the frames saw the ceiling from
  std::vector<SurveyDuplicate> duplicates;
  std::vector<std::pair<std::array<int, 2>, int>> too_rarely_seen;  // code, frames
  // Largest departures of the map from the nominal grid.
  double largest_shift_m = 0.0;
  std::array<int, 2> largest_shift_code{};
  double largest_turn_rad = 0.0;
  std::array<int, 2> largest_turn_code{};
  double tilt_x_rad = 0.0, tilt_y_rad = 0.0;  // the camera's mounting tilt found
  double marker_size = 1.0;                   // the markers' size as detected, relative to nominal
  // Each input frame's camera as adjusted (x, y on the floor, yaw); frames
  // without a used sighting keep their starting value and are not `used`.
  std::vector<std::array<double, 3>> cameras;
  std::vector<bool> used;
  // 1-sigma of the estimated camera terms (fx, fy, k1, k2, cx, cy) and
  // tilt, from the adjustment's covariance (known_map only; else 0).
  std::array<double, 6> sigma_intrinsics{};
  std::array<double, 2> sigma_tilt_rad{};
};

// Errors say why nothing could be mapped (no frame with a pose, no marker
// seen often enough, the solver failing).
Result<SurveyReport> survey_ceiling(const PipelineConfig& config,
                                    const std::vector<SurveyFrame>& frames,
                                    const SurveyOptions& options);

}  // namespace ceilpose
