// ceilposectl render: writes a simulated recording (SPEC §4) with ground
// truth for one of the simulator's named scenario sets.
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "calibration/board_spec.h"
#include "calibration/camera_info_file.h"
#include "calibration/map_file.h"
#include "config/service_config.h"
#include "core/output_guard.h"
#include "ctl/calibration_options.h"
#include "ctl/command_registry.h"
#include "recording/recording_writer.h"
#include "sim/checkerboard.h"
#include "sim/laid_ceiling.h"
#include "sim/renderer.h"
#include "sim/scenarios.h"

namespace ceilpose::ctl {
namespace {

struct RenderArgs {
  std::string scenario;
  std::string out_dir;
  std::string config_file;
  std::string camera_file;       // --camera: the camera, declared and rendered
  std::string true_camera_file;  // --true-camera: renders with it, declares the other
  std::string ceiling = "nominal";
  uint64_t ceiling_seed = 0;  // 0: --seed
  std::string truth_map_file;
  std::string board = "checkerboard:9x6:0.03";
  std::optional<double> readout_ms;  // --readout-ms: over the configuration's camera.readout_ms
  int frames = 100;
  uint64_t seed = 1;
  bool list = false;
};

// Fails with the message printed and the exit code set.
bool report(const Result<void>& r, int code) {
  if (r) return true;
  std::cerr << "ceilposectl render: " << r.error().message << "\n";
  set_exit_code(code);
  return false;
}

std::string catalog_text() {
  std::string text;
  for (const auto& [name, description] : sim::scenario_catalog())
    text += "  " + name + std::string(name.size() < 15 ? 15 - name.size() : 1, ' ') + description +
            "\n";
  text +=
      "  checkerboard   views of a checkerboard (--board) for `calibrate camera`: 0.35-0.9 m, "
      "tilted 10-45 deg, no ground truth\n";
  return text;
}

// Views of a checkerboard (for `calibrate camera`) instead of the ceiling:
// no ground-truth columns; the camera seen through is options.intrinsics.
void render_checkerboard_set(const RenderArgs& args, const ServiceConfig& config,
                             const sim::SceneOptions& options) {
  Result<BoardSpec> spec = parse_board_spec(args.board);
  if (!report(spec ? Result<void>() : spec.error(), kExitUsage)) return;
  const sim::Checkerboard board{spec->cols, spec->rows, spec->square_m};
  const std::vector<sim::BoardPose> views =
      sim::checkerboard_views(options.intrinsics, board, args.frames, args.seed);
  RecordingCamera camera;
  camera.intrinsics = config.pipeline.intrinsics;
  camera.source =
      "synthetic: ceilpose sim, checkerboard " + args.board + ", seed " + std::to_string(args.seed);
  Result<RecordingWriter> writer = RecordingWriter::create(args.out_dir, camera);
  if (!report(writer ? Result<void>() : writer.error(), kExitFailure)) return;
  const sim::CheckerboardCamera seen_through(options.intrinsics);
  Image frame;
  for (size_t i = 0; i < views.size(); ++i) {
    seen_through.render(board, views[i], 2.0, args.seed + i, &frame);
    if (!report(writer->append(
                    frame.view(),
                    sim::kScenarioStart_ns + static_cast<int64_t>(i) * sim::kScenarioFramePeriod_ns,
                    nullptr),
                kExitFailure))
      return;
    std::fprintf(stderr, "\rrendering checkerboard: %zu/%zu", i + 1, views.size());
  }
  std::fputc('\n', stderr);
  if (!report(writer->close(), kExitFailure)) return;
  std::cerr << "wrote " << views.size() << " checkerboard views to " << args.out_dir << "\n";
  set_exit_code(kExitOk);
}

void run_render(const RenderArgs& args) {
  if (args.list) {
    std::cout << catalog_text();
    set_exit_code(kExitOk);
    return;
  }
  if (args.scenario.empty() || args.out_dir.empty()) {
    std::cerr << "ceilposectl render: --scenario and --out are required (see --list)\n";
    set_exit_code(kExitUsage);
    return;
  }
  // The truth map is written before the recording: it must not replace a
  // file render reads, nor sit inside --out, which must be empty then.
  const std::vector<NamedPath> truth_map{{"--truth-map", args.truth_map_file}};
  const std::vector<NamedPath> inputs{{"--config", args.config_file},
                                      {"--camera", args.camera_file},
                                      {"--true-camera", args.true_camera_file}};
  const std::vector<NamedPath> recording{{"--out", args.out_dir}};
  if (!report(check_outputs_are_not_inputs(truth_map, inputs), kExitUsage)) return;
  if (!args.truth_map_file.empty() && !check_outputs_are_not_inputs(truth_map, {}, recording)) {
    std::cerr << "ceilposectl render: --truth-map " << args.truth_map_file << " is inside --out "
              << args.out_dir
              << ", which must be empty for the recording; write the map beside it\n";
    set_exit_code(kExitUsage);
    return;
  }
  // SPEC defaults for the ceiling, the camera and its mount unless a
  // configuration says otherwise; the seed places fixtures and clutter and
  // draws the scenario's poses and noise.
  sim::SceneOptions options;
  options.seed = args.seed;
  ServiceConfig config = default_config();
  if (!args.config_file.empty()) {
    Result<ServiceConfig> loaded = load_config_file(args.config_file);
    if (!report(loaded ? Result<void>() : loaded.error(), kExitBadInput)) return;
    config = std::move(loaded).value();
  }
  if (!args.camera_file.empty()) config.calibration.camera_file = args.camera_file;
  config.calibration.map_file.clear();  // the ceiling is --ceiling's
  Result<ServiceConfig> calibrated = with_calibration_files(config);
  if (!report(calibrated ? Result<void>() : calibrated.error(), kExitBadInput)) return;
  config = std::move(calibrated).value();
  if (args.readout_ms) config.pipeline.intrinsics.readout_ms = *args.readout_ms;
  options.layout = config.pipeline.layout;
  options.intrinsics = config.pipeline.intrinsics;
  const CameraMount mount = config.pipeline.mount;
  // The camera the frames are seen through may differ from the one the
  // recording declares: an uncalibrated camera for `survey --intrinsics`.
  if (!args.true_camera_file.empty()) {
    Result<CameraIntrinsics> truth = read_camera_info_file(args.true_camera_file);
    if (!report(truth ? Result<void>() : truth.error(), kExitBadInput)) return;
    if (!report(check_calibration_size(*truth, args.true_camera_file, options.intrinsics.width,
                                       options.intrinsics.height, "the declared camera"),
                kExitBadInput))
      return;
    options.intrinsics = *truth;
    options.intrinsics.readout_ms = config.pipeline.intrinsics.readout_ms;
  }
  Result<sim::LaidCeiling> laid = sim::LaidCeiling::parse(
      args.ceiling, options.layout, args.ceiling_seed != 0 ? args.ceiling_seed : args.seed);
  if (!report(laid ? Result<void>() : laid.error(), kExitUsage)) return;
  for (const std::string& note : laid->notes()) std::cerr << "ceiling: " << note << "\n";
  if (!args.truth_map_file.empty() &&
      !report(write_map_file(args.truth_map_file, laid->truth_map(), options.layout), kExitFailure))
    return;
  options.laid = std::make_shared<const sim::LaidCeiling>(std::move(*laid));
  if (args.scenario == "checkerboard") return render_checkerboard_set(args, config, options);
  Result<sim::Scenario> scenario =
      sim::make_scenario(args.scenario, options, args.frames, args.seed);
  if (!scenario) {
    std::cerr << "ceilposectl render: " << scenario.error().message << "\n";
    set_exit_code(kExitUsage);
    return;
  }
  RecordingCamera camera;
  camera.intrinsics = config.pipeline.intrinsics;
  camera.source = "synthetic: ceilpose sim, scenario " + scenario->name + ", seed " +
                  std::to_string(args.seed) + ", ceiling " + args.ceiling;
  Result<RecordingWriter> writer = RecordingWriter::create(args.out_dir, camera);
  if (!writer) {
    std::cerr << "ceilposectl render: " << writer.error().message << "\n";
    set_exit_code(kExitFailure);
    return;
  }
  sim::Renderer renderer(options);
  Image frame;
  const size_t total = scenario->frames.size();
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  size_t reported_tenth = 0;
  for (size_t i = 0; i < total; ++i) {
    const sim::ScenarioFrame& f = scenario->frames[i];
    // The configured mount, with the scenario's tilt (the `tilt` set) on top.
    CameraMount frame_mount = mount;
    frame_mount.tilt_x_rad += f.mount.tilt_x_rad;
    frame_mount.tilt_y_rad += f.mount.tilt_y_rad;
    sim::render_scenario_frame(renderer, f, frame_mount, options.intrinsics.readout_ms * 1e-3,
                               &frame);
    // JPEG artefacts are already in the pixels; PNG keeps them exactly.
    Result<void> ok = writer->append(frame.view(), f.timestamp_ns, &f.pose);
    if (!ok) {
      std::cerr << (tty ? "\n" : "") << "ceilposectl render: " << ok.error().message << "\n";
      set_exit_code(kExitFailure);
      return;
    }
    const size_t tenth = (i + 1) * 10 / total;
    if (tty) {
      std::fprintf(stderr, "\rrendering %s: %zu/%zu", scenario->name.c_str(), i + 1, total);
    } else if (tenth != reported_tenth) {
      std::fprintf(stderr, "rendered %zu/%zu frames\n", i + 1, total);
      reported_tenth = tenth;
    }
  }
  if (tty) std::fputc('\n', stderr);
  Result<void> closed = writer->close();
  if (!closed) {
    std::cerr << "ceilposectl render: " << closed.error().message << "\n";
    set_exit_code(kExitFailure);
    return;
  }
  std::cerr << "wrote " << total << " frames of '" << scenario->name << "' to " << args.out_dir
            << "\n";
  set_exit_code(kExitOk);
}

void add_render_command(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand(
      "render",
      "Render a simulated recording (SPEC §4) with ground truth (gt_x_m, gt_y_m, gt_yaw_rad) for "
      "a named scenario set, by default with SPEC's ceiling and camera (640x480, fx=fy=530).\n"
      "Frames are PNG, 30 fps timestamps; the same --seed gives the same recording.\n"
      "--config takes the camera (intrinsics, distortion), its mount and the ceiling layout "
      "from a configuration file; recording.yaml then carries that camera.\n"
      "Exit 0 on success, 2 on a bad command line or unknown scenario, 4 on a malformed "
      "configuration, 1 when writing fails.");
  cmd->footer("Scenarios:\n" + catalog_text());
  cmd->add_option("--scenario", args->scenario, "Scenario set to render (see below or --list)");
  cmd->add_option("--out", args->out_dir,
                  "Recording directory to create (must not exist or be empty)");
  cmd->add_option("--config", args->config_file,
                  "Configuration file (camera, mount, ceiling layout; SPEC defaults otherwise)");
  add_camera_option(cmd, &args->camera_file);
  cmd->add_option("--true-camera", args->true_camera_file,
                  "Render through this camera (camera_info YAML, same size) while recording.yaml "
                  "declares --config's / --camera's: an uncalibrated camera");
  cmd->add_option("--ceiling", args->ceiling,
                  "Where the markers are: nominal (SPEC §1), or hand-laid[:SIGMA_MM[:SIGMA_DEG]] "
                  "(default 15 mm, 1 deg per marker; one marker 50 mm off, one missing, one code "
                  "printed twice; in SPEC §8's datum)")
      ->capture_default_str();
  cmd->add_option("--ceiling-seed", args->ceiling_seed,
                  "Seed of the hand-laid ceiling (default: --seed); the same seed lays the same "
                  "ceiling for a survey walk and for test poses");
  cmd->add_option("--board", args->board,
                  "With --scenario checkerboard: the board, checkerboard:COLSxROWS:SQUARE_M "
                  "(views at 0.35-0.9 m, tilted 10-45 deg, over the whole image)")
      ->capture_default_str();
  cmd->add_option("--truth-map", args->truth_map_file,
                  "Also write the ceiling's true map (SPEC §8) to this file");
  cmd->add_option("--readout-ms", args->readout_ms,
                  "Rolling-shutter readout, first row to last, ms (SPEC §3): the moving sets "
                  "(trajectory, drive) render each row at its own instant, and recording.yaml "
                  "declares it (default: --config's camera.readout_ms, 0 = global shutter)")
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_option("--frames", args->frames, "Number of frames")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--seed", args->seed, "Seed of poses, effects, noise, fixtures and clutter")
      ->capture_default_str();
  cmd->add_flag("--list", args->list, "List the scenario sets and exit");
  cmd->callback([args] { run_render(*args); });
}

const CommandRegistrar kRenderRegistrar{"render", &add_render_command};

}  // namespace
}  // namespace ceilpose::ctl
