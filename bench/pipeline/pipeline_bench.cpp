// Speed of Localizer::localize() (the daemon's per-frame path, filter off) on simulated ceiling
// frames with 9–12 whole markers in view, per stage and per frame, at 320×240, 640×480 and
// 1280×960 (and at 640×480 told of a 25 ms rolling-shutter readout: lsq then
// estimates the motion during it too; the positioning stage's extra time is
// the cost of issue 16), and of the AprilTag 3 detector (tag36h11, one thread, decimate 2
// and 1) on grey frames of the same size holding as many tags. Each
// AprilTag benchmark reports `x_ceilpose`: its median over the pipeline's
// median at that size, both in thread CPU time per frame (medians of CPU
// time, because the machine is shared and preemption inflates wall time); a summary table is
// printed at the end.
//   ninja -C build pipeline_bench && build/bench/pipeline/pipeline_bench
#include <apriltag.h>
#include <benchmark/benchmark.h>
#include <tag36h11.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <tuple>
#include <vector>

#include "codec/jpeg_codec.h"
#include "core/clock.h"
#include "pipeline/localizer.h"
#include "sim/camera_format.h"
#include "sim/renderer.h"
#include "sim/scenarios.h"
#include "sim/visibility.h"

namespace ceilpose {
namespace {

constexpr int kFramesPerSize = 12;

sim::SceneOptions options_for(int width_px) {
  // Same field of view at every size: the focal length scales with width.
  sim::SceneOptions o;
  const double scale = width_px / 640.0;
  o.intrinsics.width = width_px;
  o.intrinsics.height = width_px * 3 / 4;
  o.intrinsics.fx = o.intrinsics.fy = 530.0 * scale;
  o.intrinsics.cx = 0.5 * (o.intrinsics.width - 1);
  o.intrinsics.cy = 0.5 * (o.intrinsics.height - 1);
  return o;
}

PipelineConfig config_for(int width_px) {
  PipelineConfig c;
  c.intrinsics = options_for(width_px).intrinsics;
  return c;
}

// Nominal-scenario frames (random poses, read noise ≤ 3) with 9–12 whole
// markers in view, rendered once per size.
const std::vector<Image>& ceiling_frames(int width_px) {
  static std::map<int, std::vector<Image>> cache;
  auto& frames = cache[width_px];
  if (!frames.empty()) return frames;
  const sim::SceneOptions options = options_for(width_px);
  sim::Renderer renderer(options);
  const Result<sim::Scenario> scenario = sim::make_scenario("nominal", options, 200, 11);
  if (!scenario) {
    std::fprintf(stderr, "pipeline_bench: %s\n", scenario.error().message.c_str());
    return frames;
  }
  for (const sim::ScenarioFrame& f : scenario->frames) {
    const int whole = sim::count_whole_markers(options, f.pose, f.mount);
    if (whole < 9 || whole > 12) continue;
    frames.emplace_back();
    renderer.render(f.pose, f.mount, f.effects, f.seed, &frames.back());
    if (static_cast<int>(frames.size()) == kFramesPerSize) break;
  }
  return frames;
}

std::map<int, double>& pipeline_median_ns() {
  static std::map<int, double> m;
  return m;
}
std::map<std::pair<int, int>, double>& apriltag_median_ns() {
  static std::map<std::pair<int, int>, double> m;
  return m;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

void BM_Pipeline(benchmark::State& state) {
  const int width_px = static_cast<int>(state.range(0));
  const double readout_ms = static_cast<double>(state.range(1));
  const std::vector<Image>& frames = ceiling_frames(width_px);
  if (frames.empty()) {
    state.SkipWithError("no frames with 9-12 whole markers");
    return;
  }
  // The daemon's per-frame object, filter off: figures stay per frame.
  PipelineConfig config = config_for(width_px);
  config.intrinsics.readout_ms = readout_ms;
  Localizer localizer(with_mode(config, PositioningMode::kAuto, false));
  FrameInfo info;
  // Medians, not means: on a shared machine a preempted iteration would
  // otherwise dominate the figure.
  constexpr size_t kMaxSamples = 1 << 16;
  std::array<std::vector<double>, kStageCount> stage_ns;
  for (auto& v : stage_ns) v.reserve(kMaxSamples);
  std::vector<double> frame_ns, frame_cpu_ns;
  frame_ns.reserve(kMaxSamples);
  frame_cpu_ns.reserve(kMaxSamples);
  double markers = 0.0, valid = 0.0;
  size_t i = 0;
  for (auto _ : state) {
    const int64_t cpu0_ns = clock_ns(CLOCK_THREAD_CPUTIME_ID);
    info.timestamp_ns += 33'333'333;
    const Localization& loc = localizer.localize(frames[i++ % frames.size()].view(), info);
    const int64_t cpu_ns = clock_ns(CLOCK_THREAD_CPUTIME_ID) - cpu0_ns;
    benchmark::DoNotOptimize(loc.published);
    if (frame_ns.size() < kMaxSamples) {
      for (int s = 0; s < kStageCount; ++s)
        stage_ns[s].push_back(static_cast<double>(loc.stage_ns[s]));
      frame_ns.push_back(static_cast<double>(loc.localize_ns));
      frame_cpu_ns.push_back(static_cast<double>(cpu_ns));
    }
    markers += loc.markers_decoded;
    valid += loc.published.valid ? 1.0 : 0.0;
  }
  const double n = static_cast<double>(state.iterations());
  for (int s = 0; s < kStageCount; ++s) {
    state.counters[std::string(Pipeline::stage_name(s)) + "_us"] = median(stage_ns[s]) * 1e-3;
  }
  const double cpu_med = median(frame_cpu_ns);
  if (readout_ms == 0.0) pipeline_median_ns()[width_px] = cpu_med;
  state.counters["median_us"] = median(frame_ns) * 1e-3;
  state.counters["median_cpu_us"] = cpu_med * 1e-3;
  state.counters["markers"] = markers / n;
  state.counters["valid"] = valid / n;
}

// The `drive` set (a moving sequence: curves, speed changes), 120 frames at
// 30 fps, as the camera hands them over: RGB24 or YUYV 4:2:2.
constexpr int kDriveFrames = 120;
const std::vector<Image>& drive_frames(int width_px, PixelFormat format) {
  static std::map<std::pair<int, PixelFormat>, std::vector<Image>> cache;
  auto& frames = cache[{width_px, format}];
  if (!frames.empty()) return frames;
  const sim::SceneOptions options = options_for(width_px);
  sim::Renderer renderer(options);
  const Result<sim::Scenario> scenario = sim::make_scenario("drive", options, kDriveFrames, 3);
  if (!scenario) {
    std::fprintf(stderr, "pipeline_bench: %s\n", scenario.error().message.c_str());
    return frames;
  }
  Image rgb;
  for (const sim::ScenarioFrame& f : scenario->frames) {
    renderer.render(f.pose, f.mount, f.effects, f.seed, &rgb);
    frames.push_back(format == PixelFormat::kRgb24 ? rgb : sim::convert_rgb(rgb, format));
  }
  return frames;
}

std::map<std::tuple<int, int, int>, double>& drive_median_ns() {
  static std::map<std::tuple<int, int, int>, double> m;
  return m;
}

// The daemon's path on a moving robot (filter on), each frame swept whole
// at full resolution (tracking 0) or, with the fix, only in the predicted
// windows (1) or at the predicted markers' edges and dots alone (2,
// detector.track_edges, the default: its whole sweeps at half resolution),
// or each frame swept whole at half resolution (3,
// detector.halve_whole_sweeps): thread CPU time of Localizer::localize per
// frame, median over every frame of every pass through the sequence (the
// filter restarts at each pass).
// The camera formats BM_Drive's "format" argument indexes.
constexpr PixelFormat kDriveFormats[] = {PixelFormat::kRgb24, PixelFormat::kYuyv,
                                         PixelFormat::kNv12};

void BM_Drive(benchmark::State& state) {
  const int width_px = static_cast<int>(state.range(0));
  const int format = static_cast<int>(state.range(1));
  const int tracking_mode = static_cast<int>(state.range(2));
  const std::vector<Image>& frames = drive_frames(width_px, kDriveFormats[format]);
  if (frames.size() != kDriveFrames) {
    state.SkipWithError("the drive set did not render");
    return;
  }
  PipelineConfig config = config_for(width_px);
  config.detector.tracking = tracking_mode == 1 || tracking_mode == 2;
  config.detector.track_edges = tracking_mode >= 2;
  config.detector.halve_whole_sweeps = tracking_mode >= 2;
  config = with_mode(config, PositioningMode::kAuto, true);
  auto localizer = std::make_unique<Localizer>(config);
  std::vector<double> frame_cpu_ns;
  frame_cpu_ns.reserve(1 << 16);
  std::array<std::vector<double>, kStageCount> stage_ns;
  for (auto& v : stage_ns) v.reserve(1 << 16);
  double tracked = 0.0, valid = 0.0, swept = 0.0;
  size_t i = 0;
  FrameInfo info;
  for (auto _ : state) {
    if (i % frames.size() == 0) {
      state.PauseTiming();
      localizer = std::make_unique<Localizer>(config);
      info.timestamp_ns = 0;
      state.ResumeTiming();
    }
    info.timestamp_ns += 33'333'333;
    const int64_t cpu0_ns = clock_ns(CLOCK_THREAD_CPUTIME_ID);
    const Localization& loc = localizer->localize(frames[i++ % frames.size()].view(), info);
    const int64_t cpu_ns = clock_ns(CLOCK_THREAD_CPUTIME_ID) - cpu0_ns;
    benchmark::DoNotOptimize(loc.published);
    if (frame_cpu_ns.size() < frame_cpu_ns.capacity()) {
      frame_cpu_ns.push_back(static_cast<double>(cpu_ns));
      for (int s = 0; s < kStageCount; ++s)
        stage_ns[s].push_back(static_cast<double>(loc.stage_ns[s]));
    }
    tracked += loc.tracked() ? 1.0 : 0.0;
    valid += loc.published.valid ? 1.0 : 0.0;
    swept += static_cast<double>(loc.swept_px) / (frames[0].width() * frames[0].height());
  }
  const double n = static_cast<double>(state.iterations());
  const double med = median(frame_cpu_ns);
  state.counters["swept_share"] = swept / n;
  drive_median_ns()[{width_px, format, tracking_mode}] = med;
  for (int s = 0; s < kStageCount; ++s) {
    state.counters[std::string(Pipeline::stage_name(s)) + "_us"] = median(stage_ns[s]) * 1e-3;
  }
  state.counters["median_cpu_us"] = med * 1e-3;
  state.counters["tracked"] = tracked / n;
  state.counters["valid"] = valid / n;
}

// Grey frames of the same size with tag36h11 tags laid out like the
// markers (a 4 × 3 grid, each tag about as large as a marker, random
// rotation), anti-aliased by 4 × 4 supersampling, read noise σ = 3.
const std::vector<image_u8_t*>& tag_frames(int width_px) {
  static std::map<int, std::vector<image_u8_t*>> cache;
  auto& frames = cache[width_px];
  if (!frames.empty()) return frames;
  apriltag_family_t* family = tag36h11_create();
  const int height_px = width_px * 3 / 4;
  const double tag_px = 0.115 * width_px;  // black-border width ≈ a marker's 63–76 px at 640
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), jitter(-0.05, 0.05);
  std::normal_distribution<double> noise(0.0, 3.0);
  int next_id = 0;
  for (int f = 0; f < 4; ++f) {
    image_u8_t* im = image_u8_create(width_px, height_px);
    std::vector<double> level(static_cast<size_t>(width_px) * height_px, 205.0);
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 4; ++col) {
        image_u8_t* tag = apriltag_to_image(family, next_id++ % static_cast<int>(family->ncodes));
        const double cx = (col + 0.5 + jitter(rng)) * width_px / 4.0;
        const double cy = (row + 0.5 + jitter(rng)) * height_px / 3.0;
        const double a = angle(rng), ca = std::cos(a), sa = std::sin(a);
        const double cell_px = tag_px / family->width_at_border;
        const double half_px = 0.5 * tag->width * cell_px;
        const int r = static_cast<int>(std::ceil(half_px * std::sqrt(2.0))) + 1;
        for (int y = std::max(0, static_cast<int>(cy) - r);
             y < std::min(height_px, static_cast<int>(cy) + r); ++y) {
          for (int x = std::max(0, static_cast<int>(cx) - r);
               x < std::min(width_px, static_cast<int>(cx) + r); ++x) {
            double sum = 0.0;
            int inside = 0;
            for (int sy = 0; sy < 4; ++sy) {
              for (int sx = 0; sx < 4; ++sx) {
                const double dx = x + (sx + 0.5) / 4.0 - 0.5 - cx,
                             dy = y + (sy + 0.5) / 4.0 - 0.5 - cy;
                const double tx = (ca * dx + sa * dy + half_px) / cell_px;
                const double ty = (-sa * dx + ca * dy + half_px) / cell_px;
                if (tx < 0 || ty < 0 || tx >= tag->width || ty >= tag->height) continue;
                sum += tag->buf[static_cast<int>(ty) * tag->stride + static_cast<int>(tx)] ? 215.0
                                                                                           : 25.0;
                ++inside;
              }
            }
            double& l = level[static_cast<size_t>(y) * width_px + x];
            l = (sum + (16 - inside) * l) / 16.0;
          }
        }
        image_u8_destroy(tag);
      }
    }
    for (int y = 0; y < height_px; ++y)
      for (int x = 0; x < width_px; ++x)
        im->buf[y * im->stride + x] = static_cast<uint8_t>(std::clamp(
            std::lround(level[static_cast<size_t>(y) * width_px + x] + noise(rng)), 0L, 255L));
    frames.push_back(im);
  }
  tag36h11_destroy(family);
  return frames;
}

void BM_AprilTag(benchmark::State& state) {
  const int width_px = static_cast<int>(state.range(0));
  const int decimate = static_cast<int>(state.range(1));
  const std::vector<image_u8_t*>& frames = tag_frames(width_px);
  apriltag_family_t* family = tag36h11_create();
  apriltag_detector_t* detector = apriltag_detector_create();
  apriltag_detector_add_family(detector, family);
  detector->nthreads = 1;
  detector->quad_decimate = static_cast<float>(decimate);
  double tags = 0.0;
  std::vector<double> frame_ns;
  frame_ns.reserve(1 << 16);
  size_t i = 0;
  for (auto _ : state) {
    const int64_t t0 = clock_ns(CLOCK_THREAD_CPUTIME_ID);
    zarray_t* detections = apriltag_detector_detect(detector, frames[i++ % frames.size()]);
    if (frame_ns.size() < frame_ns.capacity())
      frame_ns.push_back(static_cast<double>(clock_ns(CLOCK_THREAD_CPUTIME_ID) - t0));
    tags += zarray_size(detections);
    apriltag_detections_destroy(detections);
  }
  const double n = static_cast<double>(state.iterations());
  const double med = median(frame_ns);
  state.counters["tags"] = tags / n;
  state.counters["median_cpu_ms"] = med * 1e-6;
  apriltag_median_ns()[{width_px, decimate}] = med;
  const auto it = pipeline_median_ns().find(width_px);
  if (it != pipeline_median_ns().end() && it->second > 0.0) {
    state.counters["x_ceilpose"] = med / it->second;
  }
  apriltag_detector_destroy(detector);
  tag36h11_destroy(family);
}

// Issue 29 #2: what an MJPEG camera's frame costs before the pipeline sees
// it. The ceiling frames encoded as a UVC camera does (4:2:0, quality 85),
// decoded by codec/ in full (what capture does) or at 1/2 or 1/4 scale in
// libjpeg-turbo's DCT (docs/pipeline_speed.md, "MJPEG").
void BM_MjpegDecode(benchmark::State& state) {
  const int width_px = static_cast<int>(state.range(0));
  const int scale = static_cast<int>(state.range(1));
  codec::JpegCodec codec;
  std::vector<std::vector<uint8_t>> jpegs;
  for (const Image& frame : ceiling_frames(width_px)) {
    jpegs.emplace_back();
    if (!codec.encode(frame.view(), 85, &jpegs.back())) {
      state.SkipWithError("encoding failed");
      return;
    }
  }
  Image decoded;
  std::vector<double> frame_ns;
  frame_ns.reserve(1 << 16);
  size_t i = 0, bytes = 0;
  for (auto _ : state) {
    const std::vector<uint8_t>& jpeg = jpegs[i++ % jpegs.size()];
    const int64_t t0 = clock_ns(CLOCK_THREAD_CPUTIME_ID);
    const auto ok = codec.decode(jpeg.data(), jpeg.size(), PixelFormat::kRgb24, &decoded, scale);
    if (frame_ns.size() < frame_ns.capacity())
      frame_ns.push_back(static_cast<double>(clock_ns(CLOCK_THREAD_CPUTIME_ID) - t0));
    if (!ok) {
      state.SkipWithError(ok.error().message.c_str());
      return;
    }
    bytes += jpeg.size();
  }
  state.counters["median_cpu_ms"] = median(frame_ns) * 1e-6;
  state.counters["kB_per_frame"] =
      static_cast<double>(bytes) / 1024.0 / static_cast<double>(state.iterations());
}

BENCHMARK(BM_Pipeline)
    ->ArgNames({"width", "readout_ms"})
    ->Args({320, 0})
    ->Args({640, 0})
    ->Args({1280, 0})
    ->Args({640, 25})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Drive)
    ->ArgsProduct({{320, 640, 1280}, {0, 1, 2}, {0, 1, 2, 3}})
    ->ArgNames({"width", "format", "tracking"})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MjpegDecode)
    ->ArgsProduct({{640, 1280}, {1, 2, 4}})
    ->ArgNames({"width", "scale"})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AprilTag)
    ->ArgsProduct({{320, 640, 1280}, {2, 1}})
    ->ArgNames({"width", "decimate"})
    ->Unit(benchmark::kMillisecond);

void print_summary() {
  std::printf("\nsummary (one thread; medians of thread CPU time per frame)\n");
  std::printf("%-10s %14s %18s %18s\n", "size", "ceilpose ms", "apriltag d2 ms (x)",
              "apriltag d1 ms (x)");
  for (const auto& [width_px, med_ns] : pipeline_median_ns()) {
    std::printf("%4dx%-5d %14.3f", width_px, width_px * 3 / 4, med_ns * 1e-6);
    for (int decimate : {2, 1}) {
      const auto it = apriltag_median_ns().find({width_px, decimate});
      if (it == apriltag_median_ns().end()) {
        std::printf(" %18s", "-");
      } else {
        std::printf(" %10.3f (%5.1fx)", it->second * 1e-6, it->second / med_ns);
      }
    }
    std::printf("\n");
  }
  if (drive_median_ns().empty()) return;
  std::printf("\ndrive set, filter on (medians of thread CPU time per frame, ms; x AprilTag d2)\n");
  std::printf("%-10s %-6s %16s %16s %8s %16s %8s %16s %8s\n", "size", "pixels", "full sweeps",
              "tracked", "ratio", "edges tracked", "ratio", "halved sweeps", "ratio");
  for (int width_px : {320, 640, 1280}) {
    for (int format : {0, 1, 2}) {
      const auto full = drive_median_ns().find({width_px, format, 0});
      if (full == drive_median_ns().end()) continue;
      const auto tag = apriltag_median_ns().find({width_px, 2});
      const double tag_ns = tag == apriltag_median_ns().end() ? 0.0 : tag->second;
      std::printf("%4dx%-5d %-6s %7.3f (%5.1fx)", width_px, width_px * 3 / 4,
                  to_string(kDriveFormats[format]), full->second * 1e-6, tag_ns / full->second);
      for (int mode : {1, 2, 3}) {
        const auto tracked = drive_median_ns().find({width_px, format, mode});
        if (tracked == drive_median_ns().end()) {
          std::printf(" %16s %8s", "-", "-");
          continue;
        }
        std::printf(" %7.3f (%5.1fx) %8.2f", tracked->second * 1e-6, tag_ns / tracked->second,
                    tracked->second / full->second);
      }
      std::printf("\n");
    }
  }
}

}  // namespace
}  // namespace ceilpose

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  ceilpose::print_summary();
  return 0;
}
