#pragma once
// Named sets of simulated frames (poses, mounts, effects, seeds, timestamps)
// that tests, benchmarks and `ceilposectl render` share. Deterministic from
// the seed.
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/camera_model.h"
#include "core/pose.h"
#include "core/result.h"
#include "sim/effects.h"
#include "sim/renderer.h"

namespace ceilpose::sim {

// Frames of a scenario are spaced as a 30 fps camera delivers them.
inline constexpr int64_t kScenarioFramePeriod_ns = 33'333'333;
inline constexpr int64_t kScenarioStart_ns = 1'000'000'000;

struct ScenarioFrame {
  Pose2D pose;  // ground truth: the robot's pose
  CameraMount mount;
  Effects effects;
  uint64_t seed = 0;  // frame_seed for Renderer::render
  int64_t timestamp_ns = 0;
  // Sets whose robot moves along a scripted path (trajectory, drive) give it,
  // with the frame's time on it, so that a rolling shutter can render each
  // row at its own instant; null for poses drawn one by one.
  Pose2D (*path)(const CeilingLayout& layout, double t_s) = nullptr;
  double path_t_s = 0.0;
};

// The robot dt_s after the frame's time: on the path when there is one, else
// the frame's (still) pose.
inline Pose2D scenario_pose_at(const ScenarioFrame& f, const CeilingLayout& layout, double dt_s) {
  return f.path != nullptr ? f.path(layout, f.path_t_s + dt_s) : f.pose;
}

// Renders frame f through a rolling shutter of readout_s (0: global).
inline void render_scenario_frame(Renderer& renderer, const ScenarioFrame& f,
                                  const CameraMount& mount, double readout_s, Image* out) {
  if (readout_s == 0.0 || f.path == nullptr)
    return renderer.render(f.pose, mount, f.effects, f.seed, out);
  const CeilingLayout& layout = renderer.options().layout;
  renderer.render_rolling([&](double dt_s) { return scenario_pose_at(f, layout, dt_s); }, readout_s,
                          mount, f.effects, f.seed, out);
}

struct Scenario {
  std::string name;
  std::string description;
  std::vector<ScenarioFrame> frames;
};

std::vector<std::pair<std::string, std::string>> scenario_catalog();  // name, one-line description

// Errors name the scenario (unknown name, frame_count < 1, no pose found for
// `edges` within its search budget).
Result<Scenario> make_scenario(std::string_view name, const SceneOptions& options, int frame_count,
                               uint64_t seed);

}  // namespace ceilpose::sim
