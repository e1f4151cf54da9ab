#include "accuracy_support.h"

#include <gtest/gtest.h>

#include <cstdlib>

#include "capture/pixel_convert.h"
#include "pipeline/localizer.h"
#include "sim/camera_format.h"
#include "sim/renderer.h"
#include "sim/scenarios.h"
#include "sim/visibility.h"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define CEILPOSE_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define CEILPOSE_SANITIZED 1
#endif
#endif

namespace ceilpose::testing {

int accuracy_frames(int release_frames) {
  if (const char* env = std::getenv("CEILPOSE_ACCURACY_FRAMES")) {
    const int n = std::atoi(env);
    if (n > 0) return n;
  }
#if defined(CEILPOSE_SANITIZED) || defined(CEILPOSE_EMULATED)
  // Sanitizers and qemu-aarch64 (scripts/build-arm64) run this code 5-20x
  // slower: a fifth of the frames, against the same limits.
  return std::max(20, release_frames / 5);
#else
  return release_frames;
#endif
}

AccuracyReport run_scenario(const std::string& name, int frames, uint64_t seed,
                            PositioningMode mode, bool filter, const PipelineConfig& config,
                            PoseSink* also, double rendered_readout_ms, PixelFormat format,
                            bool as_recorded) {
  sim::SceneOptions options{config.layout, config.intrinsics, seed, nullptr};
  auto scenario = sim::make_scenario(name, options, frames, seed);
  if (!scenario.ok()) {
    ADD_FAILURE() << scenario.error().message;
    return {};
  }
  sim::Renderer renderer(options);
  // The scenario's mount may differ per frame: the sink asks about the frame
  // being scored.
  const sim::ScenarioFrame* current = nullptr;
  AccuracySink accuracy(config.layout.grid_m, [&](const Pose2D& truth) {
    return sim::count_whole_markers(options, truth, current->mount) > 0;
  });
  Localizer localizer(with_mode(config, mode, filter));
  Image image;
  for (const sim::ScenarioFrame& f : scenario->frames) {
    sim::render_scenario_frame(renderer, f, f.mount, rendered_readout_ms * 1e-3, &image);
    current = &f;
    FrameInfo info;
    info.timestamp_ns = f.timestamp_ns;
    info.has_ground_truth = true;
    info.ground_truth = f.pose;
    // As the camera hands the frame over (sim/camera_format.h), and as a
    // recording of it stores it.
    Image converted, recorded;
    if (format != PixelFormat::kRgb24) converted = sim::convert_rgb(image, format);
    const Image& camera = format == PixelFormat::kRgb24 ? image : converted;
    if (as_recorded) {
      if (auto ok = capture::to_rgb24(camera.view(), &recorded); !ok) {
        ADD_FAILURE() << ok.error().message;
        return {};
      }
    }
    const Localization& loc =
        localizer.localize(as_recorded ? recorded.view() : camera.view(), info);
    accuracy.consume(loc);
    if (also != nullptr) also->consume(loc);
  }
  return accuracy.report();
}

}  // namespace ceilpose::testing
