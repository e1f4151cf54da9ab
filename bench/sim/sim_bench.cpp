// Renderer speed: one frame per iteration, one thread, for the clean scene
// (scenario `random`), with sensor noise (`nominal`, what the synthetic
// camera typically renders) and with every stress effect (`stress`), at three
// resolutions.
//   ninja -C build sim_bench && build/bench/sim/sim_bench
#include <benchmark/benchmark.h>

#include "sim/renderer.h"
#include "sim/scenarios.h"

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

void BM_RenderClean(benchmark::State& state) { run(state, "random"); }
void BM_RenderNominal(benchmark::State& state) { run(state, "nominal"); }
void BM_RenderStress(benchmark::State& state) { run(state, "stress"); }

BENCHMARK(BM_RenderClean)->Arg(320)->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RenderNominal)->Arg(320)->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RenderStress)->Arg(320)->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace ceilpose::sim

BENCHMARK_MAIN();
