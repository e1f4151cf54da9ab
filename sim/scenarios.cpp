#include "sim/scenarios.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/units.h"
#include "sim/ceiling_scene.h"
#include "sim/trajectory.h"
#include "sim/visibility.h"

namespace ceilpose::sim {
namespace {

constexpr double kPi = std::numbers::pi;
// Rejection-sampling budget per frame of the `edges` set.
constexpr int kEdgeAttempts = 2000;

// Portable uniform generator (std distributions differ between standard
// libraries; scenarios must be the same everywhere for the same seed).
class Uniform {
 public:
  explicit Uniform(uint64_t seed) : state_(mix64(seed)) {}
  double operator()(double lo, double hi) {
    state_ += 0x9E3779B97F4A7C15ull;
    return lo + (hi - lo) * static_cast<double>(mix64(state_) >> 11) * 0x1.0p-53;
  }

 private:
  uint64_t state_;
};

struct Context {
  const SceneOptions& options;
  int index;
  int frame_count;
  Uniform& rng;
  double span_m() const { return (options.layout.codes() - 1) * options.layout.grid_m; }
  Pose2D random_pose() const {
    return {rng(0.0, span_m()), rng(0.0, span_m()), wrap_angle_rad(rng(-kPi, kPi))};
  }
};

using Generator = Result<ScenarioFrame> (*)(Context&);
using EffectsSetter = void (*)(Context&, Effects&);

// A set either generates whole frames or, when `generate` is null, draws a
// uniform random pose and lets `set_effects` choose the effects.
struct Entry {
  const char* name;
  const char* description;
  Generator generate;
  EffectsSetter set_effects;
};

ScenarioFrame at(const Pose2D& pose) {
  ScenarioFrame f;
  f.pose = pose;
  return f;
}

Result<ScenarioFrame> thesis_points(Context& c) {
  // The thesis's static test points in grid units, several frames each
  // (consecutive blocks), yaw varied, mild sensor noise.
  static constexpr std::array<std::array<double, 2>, 5> kPoints{
      {{1.5, 1.5}, {1.5, 2.0}, {1.5, 2.5}, {2.0, 2.5}, {2.5, 2.5}}};
  const size_t k =
      static_cast<size_t>(c.index) * kPoints.size() / static_cast<size_t>(c.frame_count);
  const double g = c.options.layout.grid_m;
  ScenarioFrame f = at({kPoints[k][0] * g, kPoints[k][1] * g, wrap_angle_rad(c.rng(-kPi, kPi))});
  f.effects.read_noise_sigma = 2.0;
  return f;
}

// A frame on a scripted path, at the frame's time.
ScenarioFrame on_path(Context& c, Pose2D (*path)(const CeilingLayout&, double)) {
  const double t_s = c.index * (kScenarioFramePeriod_ns * 1e-9);
  ScenarioFrame f = at(path(c.options.layout, t_s));
  f.path = path;
  f.path_t_s = t_s;
  f.effects.read_noise_sigma = 2.0;
  return f;
}

Result<ScenarioFrame> trajectory(Context& c) { return on_path(c, &trajectory_pose); }

Result<ScenarioFrame> drive(Context& c) { return on_path(c, &drive_pose); }

// Most sets are uniform random poses over the grid with one kind of effect;
// they differ only in how they set the effects.
void clean(Context&, Effects&) {}

void nominal(Context& c, Effects& e) { e.read_noise_sigma = c.rng(0.5, 3.0); }

void gain(Context& c, Effects& e) { e.gain = c.rng(0.45, 1.6); }

void gradient(Context& c, Effects& e) {
  e.gradient_amplitude = c.rng(0.2, 0.6);
  e.gradient_angle_rad = c.rng(-kPi, kPi);
}

void colour_cast(Context& c, Effects& e) {
  for (double& m : e.white_balance) m = c.rng(0.75, 1.25);
}

void noise(Context& c, Effects& e) {
  e.read_noise_sigma = 6.0;
  e.shot_noise_scale = c.rng(0.0, 0.5);
}

void blur(Context& c, Effects& e) { e.defocus_sigma_px = c.rng(0.6, 2.0); }

void motion_blur(Context& c, Effects& e) {
  e.motion_blur_px = c.rng(2.0, 10.0);
  e.motion_blur_angle_rad = c.rng(-kPi, kPi);
}

void jpeg(Context& c, Effects& e) { e.jpeg_quality = static_cast<int>(c.rng(40.0, 81.0)); }

void fixtures(Context& c, Effects& e) {
  e.gain = c.rng(1.0, 1.6);
  e.bloom = c.rng(0.1, 0.5);
}

void occlusion(Context& c, Effects& e) { e.occlusion_fraction = c.rng(0.05, 0.35); }

void clutter(Context&, Effects& e) { e.clutter_objects = kMaxClutterObjects / 2; }

void stress(Context& c, Effects& e) {
  // The combined levels of the project's stress accuracy target. Occlusion is left out on
  // purpose: it hides whole markers that availability counts as in view.
  e.gain = c.rng(0.45, 1.6);
  for (double& m : e.white_balance) m = c.rng(0.75, 1.25);
  e.read_noise_sigma = 6.0;  // the stress target says sigma 6: no shot noise on top
  e.defocus_sigma_px = c.rng(0.5, 1.2);
  e.motion_blur_px = c.rng(0.0, 3.0);
  e.motion_blur_angle_rad = c.rng(-kPi, kPi);
  e.gradient_amplitude = c.rng(0.0, 0.3);
  e.gradient_angle_rad = c.rng(-kPi, kPi);
  e.bloom = 0.1;
  e.clutter_objects = 6;
  e.jpeg_quality = 60;
}

Result<ScenarioFrame> tilt(Context& c) {
  ScenarioFrame f = at(c.random_pose());
  const double tilt_rad = c.rng(0.0, 3.0) * kRadPerDeg;
  const double dir_rad = c.rng(-kPi, kPi);
  f.mount.tilt_x_rad = tilt_rad * std::cos(dir_rad);
  f.mount.tilt_y_rad = tilt_rad * std::sin(dir_rad);
  f.effects.read_noise_sigma = 2.0;
  return f;
}

Result<ScenarioFrame> edges(Context& c) {
  // Rejection sampling over a band around the grid, out to 1.5 grid units
  // beyond its outer markers, keeping poses with 0–2 whole markers in view.
  const double g = c.options.layout.grid_m;
  for (int attempt = 0; attempt < kEdgeAttempts; ++attempt) {
    const Pose2D pose{c.rng(-1.5 * g, c.span_m() + 1.5 * g), c.rng(-1.5 * g, c.span_m() + 1.5 * g),
                      wrap_angle_rad(c.rng(-kPi, kPi))};
    if (count_whole_markers(c.options, pose, CameraMount{}) <= 2) {
      ScenarioFrame f = at(pose);
      f.effects.read_noise_sigma = 2.0;
      return f;
    }
  }
  return make_error("scenario 'edges': no pose with at most 2 whole markers in view found in " +
                    std::to_string(kEdgeAttempts) + " attempts for frame " +
                    std::to_string(c.index));
}

// A surveyor's walk: lanes (each from `from` to `to`, grid units) walked
// one after another at constant speed over the frames, the heading along
// the lane swinging +-25° so that every marker is seen at many yaws and
// image positions, read noise 2. Frames spread evenly along the path.
struct Lane {
  double x0, y0, x1, y1;
};

Result<ScenarioFrame> walk(Context& c, const Lane* lanes, size_t lane_count) {
  double total = 0.0;
  for (size_t k = 0; k < lane_count; ++k)
    total += std::hypot(lanes[k].x1 - lanes[k].x0, lanes[k].y1 - lanes[k].y0);
  double s = total * (c.index + 0.5) / c.frame_count;
  size_t k = 0;
  for (; k + 1 < lane_count; ++k) {
    const double len = std::hypot(lanes[k].x1 - lanes[k].x0, lanes[k].y1 - lanes[k].y0);
    if (s <= len) break;
    s -= len;
  }
  const Lane& l = lanes[k];
  const double len = std::hypot(l.x1 - l.x0, l.y1 - l.y0);
  const double f = len > 0.0 ? std::min(1.0, s / len) : 0.0;
  const double g = c.options.layout.grid_m;
  const double heading = std::atan2(l.y1 - l.y0, l.x1 - l.x0);
  ScenarioFrame fr = at({(l.x0 + f * (l.x1 - l.x0)) * g, (l.y0 + f * (l.y1 - l.y0)) * g,
                         wrap_angle_rad(heading + 25.0 * kRadPerDeg * std::sin(7.0 * s))});
  fr.effects.read_noise_sigma = 2.0;
  return fr;
}

// The whole 8 x 8 grid: East–West lanes one grid unit apart, then
// North–South lanes, so every marker is seen from every side.
Result<ScenarioFrame> survey_walk(Context& c) {
  const double hi = c.options.layout.codes() - 1;
  std::vector<Lane> lanes;
  for (int k = 0; k <= static_cast<int>(hi); ++k) {
    const bool east = k % 2 == 0;
    lanes.push_back({east ? -0.3 : hi + 0.3, 1.0 * k, east ? hi + 0.3 : -0.3, 1.0 * k});
  }
  for (int k = 0; k <= static_cast<int>(hi); ++k) {
    const bool north = k % 2 == 0;
    lanes.push_back({hi - k, north ? -0.3 : hi + 0.3, hi - k, north ? hi + 0.3 : -0.3});
  }
  return walk(c, lanes.data(), lanes.size());
}

// Two passes under separate parts of the ceiling that no frame sees
// together: North–South lanes at x = 0, 0.75, 1.5 grid units, then at
// x = hi - 1.5 .. hi. Markers between them are seen by neither.
Result<ScenarioFrame> survey_two_passes(Context& c) {
  const double hi = c.options.layout.codes() - 1;
  const Lane lanes[] = {{0.0, -0.3, 0.0, hi + 0.3},
                        {0.75, hi + 0.3, 0.75, -0.3},
                        {1.5, -0.3, 1.5, hi + 0.3},
                        {hi - 1.5, hi + 0.3, hi - 1.5, -0.3},
                        {hi - 0.75, -0.3, hi - 0.75, hi + 0.3},
                        {hi, hi + 0.3, hi, -0.3}};
  return walk(c, lanes, std::size(lanes));
}

// `calibrate mount`'s drive: at the middle of the grid, a turn in place of
// 400°, 1.2 m straight ahead, a half turn in place, 1.2 m straight back
// (shares of the frames 45/15/25/15 %), read noise 2.
Result<ScenarioFrame> mount_drive(Context& c) {
  const double g = c.options.layout.grid_m;
  const double f = (c.index + 0.5) / c.frame_count;
  const double x0 = 2.5 * g, y0 = 3.0 * g, turn1 = 400.0 * kRadPerDeg, run_m = 1.2;
  Pose2D p{x0, y0, 0.0};
  if (f < 0.45) {
    p.yaw_rad = turn1 * f / 0.45;
  } else if (f < 0.60) {
    p.yaw_rad = turn1;
    const double d = run_m * (f - 0.45) / 0.15;
    p.x_m += d * std::cos(turn1);
    p.y_m += d * std::sin(turn1);
  } else if (f < 0.85) {
    p.x_m += run_m * std::cos(turn1);
    p.y_m += run_m * std::sin(turn1);
    p.yaw_rad = turn1 + kPi * (f - 0.60) / 0.25;
  } else {
    const double d = run_m * (1.0 - (f - 0.85) / 0.15);
    p.x_m += d * std::cos(turn1);
    p.y_m += d * std::sin(turn1);
    p.yaw_rad = turn1 + kPi;
  }
  p.yaw_rad = wrap_angle_rad(p.yaw_rad);
  ScenarioFrame fr = at(p);
  fr.effects.read_noise_sigma = 2.0;
  return fr;
}

// A robot's commissioning drive (`calibrate robot`): 30 s of straight runs,
// arcs (turning while driving, radius 0.4-0.7 m), a turn in place of 372°
// and one of -172°, and a pause, centred under the grid; frames spread
// evenly over it, read noise 2. The primitives as (speed m/s, turn rad/s,
// seconds).
struct Motion {
  double v_mps, w_radps, duration_s;
};
constexpr Motion kRobotDrive[] = {{0.25, 0.0, 3.0}, {0.25, 0.4, 3.0},  {0.0, 1.0, 6.5},
                                  {0.25, 0.0, 3.0}, {0.2, -0.5, 3.5},  {0.0, -1.0, 3.0},
                                  {0.25, 0.0, 3.0}, {0.25, 0.35, 3.0}, {0.0, 0.0, 2.0}};

// The drive's pose t_s after its start, from (0, 0, 0) (exact unicycle).
Pose2D drive_by_motions(double t_s) {
  Pose2D p{0.0, 0.0, 0.0};
  for (const Motion& m : kRobotDrive) {
    const double dt = std::min(t_s, m.duration_s);
    const double th1 = p.yaw_rad + m.w_radps * dt;
    if (m.w_radps == 0.0) {
      p.x_m += m.v_mps * dt * std::cos(p.yaw_rad);
      p.y_m += m.v_mps * dt * std::sin(p.yaw_rad);
    } else {
      const double r = m.v_mps / m.w_radps;
      p.x_m += r * (std::sin(th1) - std::sin(p.yaw_rad));
      p.y_m -= r * (std::cos(th1) - std::cos(p.yaw_rad));
    }
    p.yaw_rad = th1;
    t_s -= dt;
    if (t_s <= 0.0) break;
  }
  p.yaw_rad = wrap_angle_rad(p.yaw_rad);
  return p;
}

Result<ScenarioFrame> robot_drive(Context& c) {
  double total_s = 0.0;
  for (const Motion& m : kRobotDrive) total_s += m.duration_s;
  double lo_x = 0.0, hi_x = 0.0, lo_y = 0.0, hi_y = 0.0;
  for (int k = 0; k <= 300; ++k) {
    const Pose2D p = drive_by_motions(total_s * k / 300.0);
    lo_x = std::min(lo_x, p.x_m);
    hi_x = std::max(hi_x, p.x_m);
    lo_y = std::min(lo_y, p.y_m);
    hi_y = std::max(hi_y, p.y_m);
  }
  Pose2D p = drive_by_motions(total_s * (c.index + 0.5) / c.frame_count);
  p.x_m += 0.5 * c.span_m() - 0.5 * (lo_x + hi_x);
  p.y_m += 0.5 * c.span_m() - 0.5 * (lo_y + hi_y);
  ScenarioFrame fr = at(p);
  fr.effects.read_noise_sigma = 2.0;
  return fr;
}

constexpr std::array<Entry, 22> kEntries{{
    {"thesis_points",
     "the thesis's static test points (1.5,1.5) (1.5,2.0) (1.5,2.5) (2.0,2.5) (2.5,2.5) grid "
     "units, frames split evenly between them, random yaw, read noise 2",
     &thesis_points, nullptr},
    {"random", "uniform random poses over the grid interior, random yaw, clean camera", nullptr,
     &clean},
    {"nominal", "uniform random poses, read noise sigma 0.5-3 levels (the 'nominal' accuracy set)",
     nullptr, &nominal},
    {"trajectory",
     "patrol loop over the grid at 1.2 m/s (lanes joined by U-turns of one grid unit radius), 30 "
     "fps, read noise 2",
     &trajectory, nullptr},
    {"drive",
     "a curving drive around the grid centre (curve radius 0.35 m and up), heading along the path, "
     "speed swinging smoothly between 0.1 and 1.5 m/s every 9 s, 30 fps, read noise 2",
     &drive, nullptr},
    {"gain", "random poses, exposure gain 0.45-1.6 (auto-exposure)", nullptr, &gain},
    {"gradient", "random poses, illumination gradient 20-60% in a random direction", nullptr,
     &gradient},
    {"colour_cast", "random poses, white-balance cast 0.75-1.25 per channel", nullptr,
     &colour_cast},
    {"noise", "random poses, read noise sigma 6 plus shot noise", nullptr, &noise},
    {"blur", "random poses, defocus blur sigma 0.6-2 px", nullptr, &blur},
    {"motion_blur", "random poses, motion blur 2-10 px in a random direction", nullptr,
     &motion_blur},
    {"jpeg", "random poses, JPEG round trip at quality 40-80", nullptr, &jpeg},
    {"fixtures", "random poses, saturated light fixtures with bloom 0.1-0.5, gain 1-1.6", nullptr,
     &fixtures},
    {"occlusion", "random poses, a dark occluder covering 5-35% of the image", nullptr, &occlusion},
    {"clutter", "random poses, 16 red/green non-marker objects on the ceiling", nullptr, &clutter},
    {"stress",
     "all effects combined at the stress target's levels: gain 0.45-1.6, +-25% colour cast, noise "
     "sigma 6, "
     "defocus 0.5-1.2 px, motion blur <= 3 px, gradient <= 30%, bloom 0.1, 6 clutter objects, "
     "JPEG 60 (no occlusion)",
     nullptr, &stress},
    {"tilt", "random poses, camera tilted 0-3 degrees in a random direction, read noise 2", &tilt,
     nullptr},
    {"edges",
     "poses near and beyond the grid edges with only 0-2 whole markers in view, read noise 2",
     &edges, nullptr},
    {"survey_walk",
     "a surveyor's walk for `ceilposectl survey`: East-West lanes one grid unit apart, then "
     "North-South lanes, heading swinging +-25 deg, read noise 2",
     &survey_walk, nullptr},
    {"mount_drive",
     "`calibrate mount`'s drive: a 400 deg turn in place, 1.2 m straight ahead, a half turn, "
     "1.2 m back (45/15/25/15 % of the frames; render with --config for the mount), read noise 2",
     &mount_drive, nullptr},
    {"robot_drive",
     "`calibrate robot`'s drive: 30 s of straight runs, arcs (radius 0.4-0.7 m), turns in place "
     "of 372 and -172 deg and a pause, centred under the grid, frames spread evenly (render with "
     "--config for the mount, --true-camera for the camera), read noise 2",
     &robot_drive, nullptr},
    {"survey_two_passes",
     "two survey passes that never see the same marker: North-South lanes over the western "
     "and the eastern 1.5 grid units, read noise 2",
     &survey_two_passes, nullptr},
}};

}  // namespace

std::vector<std::pair<std::string, std::string>> scenario_catalog() {
  std::vector<std::pair<std::string, std::string>> out;
  for (const Entry& e : kEntries) out.emplace_back(e.name, e.description);
  return out;
}

Result<Scenario> make_scenario(std::string_view name, const SceneOptions& options, int frame_count,
                               uint64_t seed) {
  const Entry* entry = nullptr;
  for (const Entry& e : kEntries)
    if (name == e.name) entry = &e;
  if (entry == nullptr) {
    std::string known;
    for (const Entry& e : kEntries) known += std::string(known.empty() ? "" : ", ") + e.name;
    return make_error("unknown scenario '" + std::string(name) + "' (known: " + known + ")");
  }
  if (frame_count < 1)
    return make_error("scenario '" + std::string(name) + "': frame count must be >= 1, got " +
                      std::to_string(frame_count));
  Scenario scenario{entry->name, entry->description, {}};
  scenario.frames.reserve(static_cast<size_t>(frame_count));
  uint64_t name_hash = 1469598103934665603ull;  // FNV-1a: each set draws its own numbers
  for (char ch : name) name_hash = (name_hash ^ static_cast<uint8_t>(ch)) * 1099511628211ull;
  Uniform rng(seed ^ name_hash);
  for (int i = 0; i < frame_count; ++i) {
    Context context{options, i, frame_count, rng};
    Result<ScenarioFrame> frame =
        entry->generate ? entry->generate(context) : at(context.random_pose());
    if (frame && !entry->generate) entry->set_effects(context, frame->effects);
    if (!frame) return frame.error();
    frame->seed = mix64(seed + static_cast<uint64_t>(i));
    frame->timestamp_ns = kScenarioStart_ns + i * kScenarioFramePeriod_ns;
    scenario.frames.push_back(*frame);
  }
  return scenario;
}

}  // namespace ceilpose::sim
