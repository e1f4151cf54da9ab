// The survey's bundle adjustment alone, on observations made by projecting
// the markers of a ceiling 15 mm / 1° off its grid into the cameras of a
// survey walk (0.05 px noise; no rendering, so that the solver is timed,
// not the simulator). Arguments: frames, bits (3: 8 x 8 = 64 markers,
// 4: 16 x 16 = 256). One solver thread. Counters: solve s, peak RSS of the
// process (VmHWM, grows with the largest case run so far: run one size with
// --benchmark_filter to read its own peak), observations.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "core/camera_model.h"
#include "sim/ceiling_scene.h"
#include "sim/laid_ceiling.h"
#include "sim/scenarios.h"
#include "survey/bundle_adjustment.h"

namespace ceilpose {
namespace {

double gaussian(uint64_t seed) {
  const double u1 = (static_cast<double>(sim::mix64(seed) >> 11) + 0.5) * 0x1.0p-53;
  const double u2 = static_cast<double>(sim::mix64(seed ^ 0x5bd1e995ull) >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

double peak_rss_mb() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0.0;
}

std::vector<SurveyFrame> observe(const PipelineConfig& config, const sim::LaidCeiling& laid,
                                 int frame_count) {
  sim::SceneOptions scene{config.layout, config.intrinsics, 1, nullptr};
  auto walk = sim::make_scenario("survey_walk", scene, frame_count, 11);
  std::vector<SurveyFrame> frames;
  uint64_t noise = 1;
  const CeilingLayout& l = config.layout;
  const double e[3] = {0.0, l.red_centre_e_m(), l.green_centre_e_m()};
  for (const sim::ScenarioFrame& f : walk->frames) {
    const CameraPose cam = camera_pose_from_robot(f.pose, config.mount);
    SurveyFrame frame{f.timestamp_ns,
                      {f.pose.x_m + 0.01 * gaussian(++noise), f.pose.y_m + 0.01 * gaussian(++noise),
                       f.pose.yaw_rad + 0.002 * gaussian(++noise)},
                      {}};
    for (int j = 0; j < laid.side(); ++j)
      for (int i = 0; i < laid.side(); ++i) {
        const sim::LaidMarker& m = laid.at(i, j);
        MarkerObservation o;
        o.code_i = m.code_i;
        o.code_j = m.code_j;
        bool inside = true;
        for (int p = 0; p < 3 && inside; ++p) {
          const double c = std::cos(m.yaw_rad), s = std::sin(m.yaw_rad);
          double u = 0.0, v = 0.0;
          inside = project_world_point(config.intrinsics, cam,
                                       {m.x_m + c * e[p], m.y_m + s * e[p], l.height_m}, &u, &v) &&
                   u > 40 && v > 40 && u < config.intrinsics.width - 40 &&
                   v < config.intrinsics.height - 40;
          o.points[static_cast<size_t>(p)] = {e[p], 0.0, u + 0.05 * gaussian(++noise),
                                              v + 0.05 * gaussian(++noise)};
        }
        if (!inside) continue;
        o.point_count = 3;
        o.centre_u_px = o.points[0].u_px;
        o.centre_v_px = o.points[0].v_px;
        frame.markers.push_back(o);
      }
    frames.push_back(std::move(frame));
  }
  return frames;
}

void BM_Survey(benchmark::State& state) {
  const int frame_count = static_cast<int>(state.range(0));
  PipelineConfig config;
  config.layout.bits = static_cast<int>(state.range(1));
  sim::HandLaidOptions hand;
  hand.duplicate = false;
  const sim::LaidCeiling laid = sim::LaidCeiling::hand_laid(config.layout, hand);
  const std::vector<SurveyFrame> frames = observe(config, laid, frame_count);
  SurveyOptions options;
  options.threads = 1;
  double solve_s = 0.0;
  int points = 0, markers = 0;
  for (auto _ : state) {
    auto report = survey_ceiling(config, frames, options);
    if (!report) {
      state.SkipWithError(report.error().message.c_str());
      return;
    }
    solve_s = report->solve_s;
    points = report->points;
    markers = report->map.present_count();
  }
  state.counters["solve_s"] = solve_s;
  state.counters["peak_rss_MB"] = peak_rss_mb();
  state.counters["points"] = points;
  state.counters["markers"] = markers;
}

BENCHMARK(BM_Survey)
    ->ArgsProduct({{125, 250, 500, 1000}, {3}})
    ->Args({500, 4})
    ->Args({1000, 4})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

}  // namespace
}  // namespace ceilpose

BENCHMARK_MAIN();
