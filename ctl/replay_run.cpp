#include "ctl/replay_run.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "config/service_config.h"
#include "ctl/calibration_options.h"

namespace ceilpose::ctl {
namespace {

// Frames refused for wrong heights show only "refusal":"wrong_heights"; say
// once, after the run, what distance the markers imply instead. Greyscale
// frames (refused "no_colour") are counted and named once too.
class HeightsCheck final : public PoseSink {
 public:
  explicit HeightsCheck(size_t frames) { depth_scales_.reserve(frames); }
  void consume(const Localization& loc) override {
    if (loc.measured.depth_scale > 0.0) depth_scales_.push_back(loc.measured.depth_scale);
    if (loc.refusal == Refusal::kWrongHeights) ++refused_;
    if (loc.refusal == Refusal::kNoColour) ++greyscale_;
  }
  void warn(const char* command, const PipelineConfig& config, size_t frames) {
    if (greyscale_ > 0)
      std::fprintf(stderr,
                   "ceilposectl %s: warning: %zu of %zu frames are greyscale and got no pose: the "
                   "markers are found by their red and green (record in colour)\n",
                   command, greyscale_, frames);
    if (refused_ == 0 || depth_scales_.empty()) return;
    const auto mid = depth_scales_.begin() + static_cast<ptrdiff_t>(depth_scales_.size() / 2);
    std::nth_element(depth_scales_.begin(), mid, depth_scales_.end());
    const double depth_m = config.layout.height_m - config.mount.lens_height_m;
    std::fprintf(stderr,
                 "ceilposectl %s: warning: the markers' spacing puts the ceiling %.3f m above the "
                 "lens (median of %zu frames), the configuration says %.3f m (ceiling.height_m "
                 "%.4f - mount.lens_height_m %.4f); %zu frames more than %.0f %% off got no "
                 "pose: check the heights (--config)\n",
                 command, *mid * depth_m, depth_scales_.size(), depth_m, config.layout.height_m,
                 config.mount.lens_height_m, refused_,
                 100.0 * config.positioning.max_depth_scale_error);
  }

 private:
  std::vector<double> depth_scales_;
  size_t refused_ = 0;
  size_t greyscale_ = 0;
};

}  // namespace

void add_replay_options(CLI::App* cmd, ReplayArgs* args) {
  cmd->add_option("--replay", args->dir, "Recording directory (SPEC §4)")->required();
  cmd->add_option("--config", args->config_file,
                  "Configuration file overriding SPEC's defaults (the camera intrinsics come "
                  "from the recording's recording.yaml unless a calibration file is given)");
  add_calibration_options(cmd, &args->calibration);
  cmd->add_flag("--filter", args->filter,
                "Apply the daemon's temporal filter (default: every frame solved on its own)");
  cmd->add_option("--predict-ms", args->predict_ms,
                  "With the filter (implied): predict each pose MS milliseconds past its frame's "
                  "time, as a controller asking \"where am I now?\" gets when the frame is MS "
                  "old (SPEC §5)")
      ->check(CLI::Range(-10000.0, 10000.0));
  cmd->add_option("--mode", args->mode_text, "Positioning mode: auto | axes | barycentric | lsq")
      ->check(CLI::IsMember(positioning_mode_names()));
  cmd->add_option("--decode-threads", args->decode_threads,
                  "Threads decoding frames ahead of localization (default: CPUs, at most 4); "
                  "frames are still localized one at a time, in order")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
}

int prepare_replay(const ReplayArgs& args, const char* command, ReplaySetup* setup) {
  PositioningMode mode = PositioningMode::kAuto;
  CalibrationFiles files;
  if (!args.config_file.empty()) {
    auto loaded = load_config_file(args.config_file);
    if (!loaded.ok()) {
      std::fprintf(stderr, "ceilposectl %s: %s\n", command, loaded.error().message.c_str());
      return kExitBadInput;
    }
    setup->config = loaded->pipeline;
    mode = loaded->pipeline.positioning.mode;
    files = loaded->calibration;
  }
  if (!args.calibration.camera_file.empty()) files.camera_file = args.calibration.camera_file;
  if (!args.calibration.map_file.empty()) files.map_file = args.calibration.map_file;
  if (!args.mode_text.empty() && !parse_positioning_mode(args.mode_text, &mode)) {
    std::fprintf(stderr, "ceilposectl %s: --mode %s: expected one of %s\n", command,
                 args.mode_text.c_str(), positioning_mode_list().c_str());
    return kExitUsage;
  }
  setup->config.positioning.mode = mode;
  setup->config.filter.enabled = args.filter || args.predict_ms.has_value();
  // The one horizon rule (core/motion_model.h): a prediction further than
  // the filter's horizon is refused by every client, so here too. NaN fails.
  const double horizon_ms = setup->config.filter.predict_horizon_ms;
  if (args.predict_ms && !(std::abs(*args.predict_ms) <= horizon_ms)) {
    std::fprintf(stderr,
                 "ceilposectl %s: --predict-ms %g: beyond the filter's horizon of %g ms "
                 "(filter.predict_horizon_ms; raise it with --config)\n",
                 command, *args.predict_ms, horizon_ms);
    return kExitUsage;
  }
  auto reader = RecordingReader::open(args.dir);
  if (!reader.ok()) {
    std::fprintf(stderr, "ceilposectl %s: %s\n", command, reader.error().message.c_str());
    return kExitBadInput;
  }
  setup->config.intrinsics = reader->camera().intrinsics;
  const CameraIntrinsics& k = setup->config.intrinsics;
  auto calibrated =
      load_calibration_files(files,
                             "the recording " + args.dir + " (" + std::to_string(k.width) + "x" +
                                 std::to_string(k.height) + ")",
                             &setup->config);
  if (!calibrated) {
    std::fprintf(stderr, "ceilposectl %s: %s\n", command, calibrated.error().message.c_str());
    return kExitBadInput;
  }
  setup->reader.emplace(std::move(reader.value()));
  return kExitOk;
}

int run_replay(const ReplayArgs& args, const char* command, const ReplaySetup& setup,
               std::span<PoseSink* const> sinks) {
  const RecordingReader& reader = *setup.reader;
  Localizer localizer(setup.config);
  localizer.defer_scheduled_sweeps(true);  // as the daemon does
  FramePrefetcher frames(reader, args.decode_threads);
  if (frames.threads() < args.decode_threads) {
    const CameraIntrinsics& k = reader.camera().intrinsics;
    std::fprintf(stderr,
                 "ceilposectl %s: decoding on %d threads, not %d: %dx%d frames on more would "
                 "hold over %zu MiB\n",
                 command, frames.threads(), args.decode_threads, k.width, k.height,
                 FramePrefetcher::kDecodeBudgetBytes >> 20);
  }
  const size_t total = reader.rows().size();
  HeightsCheck heights(total);
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  for (size_t i = 0; i < total; ++i) {
    auto loaded = frames.next();
    if (!loaded.ok()) {
      if (tty) std::fputc('\n', stderr);
      std::fprintf(stderr, "ceilposectl %s: %s\n", command, loaded.error().message.c_str());
      return kExitBadInput;
    }
    const RecordingRow& row = reader.rows()[i];
    FrameInfo info;
    info.timestamp_ns = row.timestamp_ns;
    info.index = row.index;
    info.has_ground_truth = row.has_ground_truth;
    info.ground_truth = row.ground_truth;
    const Localization& loc = localizer.localize((*loaded)->view(), info);
    heights.consume(loc);
    for (PoseSink* sink : sinks) sink->consume(loc);
    localizer.check_scheduled((*loaded)->view());
    if (tty && (i % 25 == 0 || i + 1 == total)) {
      std::fprintf(stderr, "\r%s: frame %zu/%zu", command, i + 1, total);
      if (i + 1 == total) std::fputc('\n', stderr);
    }
  }
  heights.warn(command, setup.config, total);
  return kExitOk;
}

}  // namespace ceilpose::ctl
