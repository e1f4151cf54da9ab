// ceilposectl render: writes a simulated recording (SPEC §4) with ground
// truth for one of the simulator's named scenario sets.
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "config/service_config.h"
#include "ctl/command_registry.h"
#include "recording/recording_writer.h"
#include "sim/renderer.h"
#include "sim/scenarios.h"

namespace ceilpose::ctl {
namespace {

struct RenderArgs {
  std::string scenario;
  std::string out_dir;
  std::string config_file;
  int frames = 100;
  uint64_t seed = 1;
  bool list = false;
};

std::string catalog_text() {
  std::string text;
  for (const auto& [name, description] : sim::scenario_catalog())
    text += "  " + name + std::string(name.size() < 15 ? 15 - name.size() : 1, ' ') + description +
            "\n";
  return text;
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
  // SPEC defaults for the ceiling, the camera and its mount unless a
  // configuration says otherwise; the seed places fixtures and clutter and
  // draws the scenario's poses and noise.
  sim::SceneOptions options;
  options.seed = args.seed;
  CameraMount mount;
  if (!args.config_file.empty()) {
    Result<ServiceConfig> config = load_config_file(args.config_file);
    if (!config) {
      std::cerr << "ceilposectl render: " << config.error().message << "\n";
      set_exit_code(kExitBadInput);
      return;
    }
    options.layout = config->pipeline.layout;
    options.intrinsics = config->pipeline.intrinsics;
    mount = config->pipeline.mount;
  }
  Result<sim::Scenario> scenario =
      sim::make_scenario(args.scenario, options, args.frames, args.seed);
  if (!scenario) {
    std::cerr << "ceilposectl render: " << scenario.error().message << "\n";
    set_exit_code(kExitUsage);
    return;
  }
  RecordingCamera camera;
  camera.intrinsics = options.intrinsics;
  camera.source =
      "synthetic: ceilpose sim, scenario " + scenario->name + ", seed " + std::to_string(args.seed);
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
    renderer.render(f.pose, frame_mount, f.effects, f.seed, &frame);
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
  cmd->add_option("--frames", args->frames, "Number of frames")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--seed", args->seed, "Seed of poses, effects, noise, fixtures and clutter")
      ->capture_default_str();
  cmd->add_flag("--list", args->list, "List the scenario sets and exit");
  cmd->callback([args] { run_render(*args); });
}

const CommandRegistrar kReg{"render", &add_render_command};

}  // namespace
}  // namespace ceilpose::ctl
