#pragma once
// Shared by `locate` and `evaluate`: the configuration (SPEC defaults,
// --config, the recording's camera) and the frame loop that localizes every
// frame of a recording in order. Header-only because ceilposectl compiles
// only main.cpp, the registry and *_command.cpp.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "config/service_config.h"
#include "core/clock.h"
#include "core/image.h"
#include "ctl/command_registry.h"
#include "pipeline/pipeline.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/temporal_filter.h"
#include "recording/frame_prefetcher.h"
#include "recording/recording_reader.h"

namespace ceilpose::ctl {

struct ReplayArgs {
  std::string dir;
  std::string config_file;
  std::string mode_text;  // empty: the configuration's mode (SPEC default auto)
  bool filter = false;
  int decode_threads = FramePrefetcher::default_threads();
};

// Adds --replay, --config, --filter and --mode to a sub-command.
inline void add_replay_options(CLI::App* cmd, ReplayArgs* args) {
  cmd->add_option("--replay", args->dir, "Recording directory (SPEC §4)")->required();
  cmd->add_option("--config", args->config_file,
                  "Configuration file overriding SPEC's defaults (the camera intrinsics always "
                  "come from the recording's recording.yaml)");
  cmd->add_flag("--filter", args->filter,
                "Apply the daemon's temporal filter (default: every frame solved on its own)");
  cmd->add_option("--mode", args->mode_text, "Positioning mode: auto | axes | barycentric | lsq")
      ->check(CLI::IsMember({"auto", "axes", "barycentric", "lsq"}));
  cmd->add_option("--decode-threads", args->decode_threads,
                  "Threads decoding frames ahead of localization (default: CPUs, at most 4); "
                  "frames are still localized one at a time, in order")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
}

struct ReplaySetup {
  PipelineConfig config;
  PositioningMode mode = PositioningMode::kAuto;
  std::optional<RecordingReader> reader;
};

// Loads the configuration and opens the recording. On failure prints the
// error (naming file and line) and returns the exit code, else kExitOk.
inline int prepare_replay(const ReplayArgs& args, const char* command, ReplaySetup* setup) {
  if (!args.config_file.empty()) {
    auto loaded = load_config_file(args.config_file);
    if (!loaded.ok()) {
      std::fprintf(stderr, "ceilposectl %s: %s\n", command, loaded.error().message.c_str());
      return kExitBadInput;
    }
    setup->config = loaded->pipeline;
    setup->mode = loaded->positioning_mode;
  }
  if (!args.mode_text.empty() && !parse_positioning_mode(args.mode_text, &setup->mode)) {
    std::fprintf(stderr, "ceilposectl %s: --mode %s: expected auto, axes, barycentric or lsq\n",
                 command, args.mode_text.c_str());
    return kExitUsage;
  }
  auto reader = RecordingReader::open(args.dir);
  if (!reader.ok()) {
    std::fprintf(stderr, "ceilposectl %s: %s\n", command, reader.error().message.c_str());
    return kExitBadInput;
  }
  setup->config.intrinsics = reader->camera().intrinsics;
  setup->reader.emplace(std::move(reader.value()));
  return kExitOk;
}

// One localized frame: the row of frames.csv, the (filtered when asked)
// estimate, the decoded marker count and the processing time.
struct ReplayFrame {
  size_t position = 0;
  const RecordingRow* row = nullptr;
  PoseEstimate estimate;
  int markers_decoded = 0;
  int64_t proc_ns = 0;
};

// After a run: frames that positioning refused because the markers' spacing
// contradicts the configured heights (the positioner's own rule,
// depth_scale_contradicts_heights) would otherwise show only "valid":false;
// say why, once, with the distance the markers imply.
inline void warn_if_heights_disagree(const char* command, const PipelineConfig& config,
                                     std::vector<double>* depth_scales) {
  const auto refused = std::count_if(depth_scales->begin(), depth_scales->end(), [&](double s) {
    return depth_scale_contradicts_heights(config.positioning, s);
  });
  if (refused == 0) return;
  const auto mid = depth_scales->begin() + static_cast<ptrdiff_t>(depth_scales->size() / 2);
  std::nth_element(depth_scales->begin(), mid, depth_scales->end());
  const double depth_m = config.layout.height_m - config.mount.lens_height_m;
  std::fprintf(stderr,
               "ceilposectl %s: warning: the markers' spacing puts the ceiling %.3f m above the "
               "lens (median of %zu frames), the configuration says %.3f m (ceiling.height_m "
               "%.4f - mount.lens_height_m %.4f); %td frames more than %.0f %% off got no pose: "
               "check the heights (--config)\n",
               command, *mid * depth_m, depth_scales->size(), depth_m, config.layout.height_m,
               config.mount.lens_height_m, refused,
               100.0 * config.positioning.max_depth_scale_error);
}

// Localizes every frame in order, as fast as possible. Returns the exit code:
// kExitBadInput (message printed) when a frame cannot be loaded.
inline int run_replay(const ReplayArgs& args, const char* command, const ReplaySetup& setup,
                      const std::function<void(const ReplayFrame&)>& on_frame) {
  const RecordingReader& reader = *setup.reader;
  Pipeline pipeline(setup.config);
  TemporalFilter filter(setup.config.filter);
  auto result = std::make_unique<FrameResult>();
  FramePrefetcher frames(reader, args.decode_threads);
  const size_t total = reader.rows().size();
  std::vector<double> depth_scales;
  depth_scales.reserve(total);
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  for (size_t i = 0; i < total; ++i) {
    auto loaded = frames.next();
    if (!loaded.ok()) {
      if (tty) std::fputc('\n', stderr);
      std::fprintf(stderr, "ceilposectl %s: %s\n", command, loaded.error().message.c_str());
      return kExitBadInput;
    }
    const RecordingRow& row = reader.rows()[i];
    const int64_t start_ns = monotonic_ns();
    pipeline.process((*loaded)->view(), setup.mode, result.get());
    if (result->estimate.depth_scale > 0.0) depth_scales.push_back(result->estimate.depth_scale);
    ReplayFrame out;
    out.estimate =
        args.filter ? filter.update(result->estimate, row.timestamp_ns) : result->estimate;
    out.proc_ns = monotonic_ns() - start_ns;
    out.position = i;
    out.row = &row;
    out.markers_decoded = result->marker_count;
    on_frame(out);
    if (tty && (i % 25 == 0 || i + 1 == total)) {
      std::fprintf(stderr, "\r%s: frame %zu/%zu", command, i + 1, total);
      if (i + 1 == total) std::fputc('\n', stderr);
    }
  }
  warn_if_heights_disagree(command, setup.config, &depth_scales);
  return kExitOk;
}

}  // namespace ceilpose::ctl
