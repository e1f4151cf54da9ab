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
};

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
