// Renderer speed: one frame per iteration, one thread, for the clean scene
// (scenario `random`), with sensor noise (`nominal`, what the synthetic
// camera typically renders) and with every stress effect (`stress`), at three
// resolutions; and the synthetic camera's frame as the daemon gets it
// (TrajectoryCamera, default effects, RGB24 or YUYV), which must stay under
// a frame period for the camera to deliver its rate (60 fps: 16.7 ms).
//   ninja -C build sim_bench && build/bench/sim/sim_bench
#include <benchmark/benchmark.h>

#include "sim/renderer.h"
#include "sim/scenarios.h"
#include "sim/trajectory_camera.h"

namespace ceilpose::sim {
namespace {

void run(benchmark::State& state, const char* scenario_name) {
  SceneOptions options;
  options.intrinsics = scaled_default_intrinsics(static_cast<int>(state.range(0)));
  Renderer renderer(options);
  const Result<Scenario> scenario = make_scenario(scenario_name, options, 64, 5);
  if (!scenario) {
    state.SkipWithError(scenario.error().message.c_str());
    return;
  }
  Image frame;
  size_t i = 0;
  for (auto _ : state) {
    const ScenarioFrame& f = scenario->frames[i++ % scenario->frames.size()];
    renderer.render(f.pose, f.mount, f.effects, f.seed, &frame);
    benchmark::DoNotOptimize(frame.data());
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_TrajectoryCamera(benchmark::State& state) {
  TrajectoryCameraOptions options;
  options.scene.intrinsics = scaled_default_intrinsics(static_cast<int>(state.range(0)));
  options.format = state.range(1) != 0 ? PixelFormat::kYuyv : PixelFormat::kRgb24;
  TrajectoryCamera camera(options);
  Image frame;
  frame.resize(options.scene.intrinsics.width, options.scene.intrinsics.height, options.format);
  Pose2D truth;
  uint64_t tick = 0;
  for (auto _ : state) {
    camera.generate(static_cast<int64_t>(tick) * 16'666'667, tick, &frame, &truth);
    ++tick;
    benchmark::DoNotOptimize(frame.data());
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_RenderClean(benchmark::State& state) { run(state, "random"); }
void BM_RenderNominal(benchmark::State& state) { run(state, "nominal"); }
void BM_RenderStress(benchmark::State& state) { run(state, "stress"); }

BENCHMARK(BM_RenderClean)->Arg(320)->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RenderNominal)->Arg(320)->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RenderStress)->Arg(320)->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TrajectoryCamera)
    ->ArgsProduct({{640, 1280}, {0, 1}})
    ->ArgNames({"width", "yuyv"})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace ceilpose::sim

BENCHMARK_MAIN();
