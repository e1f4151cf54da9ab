// ceilposectl survey: maps a hand-laid ceiling from one or more walks under
// it (SPEC §10): every frame's decoded markers into one bundle adjustment
// (survey/), the map written as SPEC §8, the camera as SPEC §9 with
// --intrinsics.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "calibration/camera_info_file.h"
#include "calibration/map_file.h"
#include "calibration/mount_estimate.h"
#include "calibration/mount_fragment.h"
#include "core/output_guard.h"
#include "core/units.h"
#include "ctl/calibration_options.h"
#include "ctl/command_registry.h"
#include "ctl/replay_run.h"
#include "ctl/survey_frames.h"
#include "survey/bundle_adjustment.h"

namespace ceilpose::ctl {
namespace {

struct SurveyArgs {
  std::vector<std::string> dirs;
  std::string config_file;
  std::string camera_file;
  std::string out_file;
  std::string camera_out_file;
  std::string mount_out_file;
  bool intrinsics = false;
  double prior_sigma_mm = 50.0;
  int threads = 1;
};

void print_summary(const SurveyReport& r, const SurveyArgs& args, double grid_m) {
  const CeilingMap& map = r.map;
  std::vector<double> sigmas;
  double max_sigma_yaw = 0.0;
  for (int j = 0; j < map.codes(); ++j)
    for (int i = 0; i < map.codes(); ++i)
      if (const MarkerPlacement* p = map.find(i, j)) {
        sigmas.push_back(p->sigma_m);
        max_sigma_yaw = std::max(max_sigma_yaw, p->sigma_yaw_rad);
      }
  std::sort(sigmas.begin(), sigmas.end());
  std::fprintf(stderr,
               "survey: bundle adjustment: %d frames, %d marker sightings, %d image points; %d "
               "iterations in %.2f s\n",
               r.frames_used, r.sightings, r.points, r.iterations, r.solve_s);
  std::fprintf(stderr, "survey: RMS reprojection error %.3f px (%.3f px on the nominal grid)\n",
               r.rms_px, r.initial_rms_px);
  std::fprintf(stderr,
               "survey: %d markers mapped; sigma median %.3f mm, max %.3f mm; yaw sigma max "
               "%.4f deg\n",
               map.present_count(), 1000.0 * sigmas[sigmas.size() / 2], 1000.0 * sigmas.back(),
               kDegPerRad * max_sigma_yaw);
  std::fprintf(stderr,
               "survey: largest corrections from nominal: (%d, %d) moved %.1f mm, (%d, %d) turned "
               "%.2f deg\n",
               r.largest_shift_code[0], r.largest_shift_code[1], 1000.0 * r.largest_shift_m,
               r.largest_turn_code[0], r.largest_turn_code[1], kDegPerRad * r.largest_turn_rad);
  if (!args.intrinsics)
    std::fprintf(stderr, "survey: camera tilt found: %.3f deg about x, %.3f deg about y\n",
                 kDegPerRad * r.tilt_x_rad, kDegPerRad * r.tilt_y_rad);
  std::fprintf(stderr, "survey: markers as detected: %.3f %% of their nominal size\n",
               100.0 * r.marker_size);
  for (const SurveyDuplicate& d : r.duplicates)
    std::fprintf(stderr,
                 "survey: code (%d, %d) is also on the ceiling at (%.3f, %.3f) m, near node (%ld, "
                 "%ld), seen in %d frames: printed twice? That one is not mapped; replace it\n",
                 d.code_i, d.code_j, d.x_m, d.y_m, std::lround(d.x_m / grid_m),
                 std::lround(d.y_m / grid_m), d.frames);
  for (const auto& [code, frames] : r.too_rarely_seen)
    std::fprintf(stderr, "survey: (%d, %d) not mapped: decoded in only %d frame(s)\n", code[0],
                 code[1], frames);
  if (r.groups > 1)
    std::fprintf(stderr,
                 "survey: warning: the walk saw the ceiling in %d separate parts that no frame "
                 "links; their placement relative to each other rests on the nominal-spot prior "
                 "(sigma %.0f mm): walk across the gaps\n",
                 r.groups, args.prior_sigma_mm);
}

FrameSources sources_of(const SurveyArgs& args) {
  FrameSources sources;
  sources.dirs = args.dirs;
  sources.config_file = args.config_file;
  sources.calibration.camera_file = args.camera_file;
  return sources;
}

void run_survey(const SurveyArgs& args) {
  std::vector<NamedPath> dirs;
  for (const std::string& dir : args.dirs) dirs.push_back({"--replay", dir});
  if (auto clash = check_outputs_are_not_inputs(
          {{"--out", args.out_file},
           {"--camera-out", args.camera_out_file},
           {"--mount-out", args.mount_out_file}},
          {{"--config", args.config_file}, {"--camera", args.camera_file}}, dirs);
      !clash) {
    std::fprintf(stderr, "ceilposectl survey: %s\n", clash.error().message.c_str());
    return set_exit_code(kExitUsage);
  }
  std::vector<SurveyFrame> frames;
  PipelineConfig config;
  if (int rc = collect_survey_frames(sources_of(args), "survey", nullptr, &config, &frames);
      rc != kExitOk)
    return set_exit_code(rc);
  SurveyOptions options;
  options.prior_sigma_m = args.prior_sigma_mm / 1000.0;
  options.estimate_intrinsics = args.intrinsics;
  options.threads = args.threads;
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  options.progress = [tty](const std::string& line) {
    std::fprintf(stderr, tty ? "\rsurvey: %s   " : "survey: %s\n", line.c_str());
  };
  auto report = survey_ceiling(config, frames, options);
  if (tty) std::fputc('\n', stderr);
  // The detector corrects its centroids for the lens distortion it is told
  // of; decoded with the declared camera, frames of a distorting lens give
  // centroids that the bundle adjustment reads as a focal length 0.4 % short
  // (k1 = -0.08). So the frames are decoded again with the camera found and
  // surveyed once more.
  if (report && args.intrinsics) {
    const CameraIntrinsics found = report->intrinsics;
    std::fprintf(stderr, "survey: decoding again with the camera found (fx %.2f px, k1 %.4f)\n",
                 found.fx, found.distortion[0]);
    if (int rc = collect_survey_frames(sources_of(args), "survey", &found, &config, &frames);
        rc != kExitOk)
      return set_exit_code(rc);
    report = survey_ceiling(config, frames, options);
    if (tty) std::fputc('\n', stderr);
  }
  if (!report) {
    std::fprintf(stderr, "ceilposectl survey: %s\n", report.error().message.c_str());
    return set_exit_code(kExitFailure);
  }
  print_summary(*report, args, config.layout.grid_m);
  // A walk with turns in place and straight runs also tells where the
  // camera sits on the robot; with --intrinsics that mount also absorbs the
  // principal point the survey held.
  std::vector<CameraSample> track;
  for (size_t f = 0; f < frames.size(); ++f)
    if (report->used[f])
      track.push_back({frames[f].timestamp_ns * 1e-9, report->cameras[f][0], report->cameras[f][1],
                       report->cameras[f][2]});
  auto mount = estimate_mount(track);
  if (mount) {
    std::fprintf(stderr,
                 "survey: the walk's turns in place give the mount: camera %.2f +- %.2f mm "
                 "forward, %.2f +- %.2f mm left of the robot origin, turned %.3f +- %.3f deg\n",
                 1000.0 * mount->offset_forward_m, 1000.0 * mount->sigma_forward_m,
                 1000.0 * mount->offset_left_m, 1000.0 * mount->sigma_left_m,
                 kDegPerRad * mount->yaw_rad, kDegPerRad * mount->sigma_yaw_rad);
  } else if (!args.mount_out_file.empty()) {
    std::fprintf(stderr, "ceilposectl survey: --mount-out: %s; nothing was written\n",
                 mount.error().message.c_str());
    return set_exit_code(kExitFailure);
  }
  std::string held;
  if (args.intrinsics) {
    const CameraIntrinsics& k = report->intrinsics;
    std::fprintf(stderr,
                 "survey: camera: fx %.2f fy %.2f px, k1 %.5f k2 %.5f estimated; cx %.2f cy %.2f "
                 "px, p1 %.6f p2 %.6f k3 %.5f held at the declared camera's\n",
                 k.fx, k.fy, k.distortion[0], k.distortion[1], k.cx, k.cy, k.distortion[2],
                 k.distortion[3], k.distortion[4]);
    held = mount ? "a principal point off-centre cannot be told from a camera mounted "
                   "off-centre: the mount the walk gave absorbs it; use this camera with that "
                   "mount (--mount-out)"
                 : "a principal point off-centre cannot be told from a camera mounted "
                   "off-centre: the robot's origin is undetermined until `calibrate robot`, "
                   "`calibrate mount` or a checkerboard (`calibrate camera`) fixes it";
    std::fprintf(stderr, "survey: %s\n", held.c_str());
  }
  if (auto wrote = write_map_file(args.out_file, report->map, config.layout); !wrote) {
    std::fprintf(stderr, "ceilposectl survey: %s\n", wrote.error().message.c_str());
    return set_exit_code(kExitFailure);
  }
  std::fprintf(stderr, "survey: wrote the map to %s\n", args.out_file.c_str());
  if (args.intrinsics) {
    const std::string text =
        "# ceilposectl survey --intrinsics: fx, fy, k1, k2 estimated; cx, "
        "cy, p1, p2, k3 held at the declared camera's.\n# " +
        held + ".\n";
    if (auto wrote =
            write_camera_info_file(args.camera_out_file, report->intrinsics, "ceilpose", text);
        !wrote) {
      std::fprintf(stderr, "ceilposectl survey: %s\n", wrote.error().message.c_str());
      return set_exit_code(kExitFailure);
    }
    std::fprintf(stderr, "survey: wrote the camera to %s\n", args.camera_out_file.c_str());
  }
  if (mount && !args.mount_out_file.empty()) {
    const MountFragment fragment = fragment_of(
        *mount, config.mount, "ceilposectl survey: the walk's turns in place and straight runs.");
    if (auto wrote = write_mount_fragment(args.mount_out_file, fragment); !wrote) {
      std::fprintf(stderr, "ceilposectl survey: %s\n", wrote.error().message.c_str());
      return set_exit_code(kExitFailure);
    }
    std::fprintf(stderr, "survey: wrote the mount to %s\n", args.mount_out_file.c_str());
  }
  set_exit_code(kExitOk);
}

void add_survey_command(CLI::App& app) {
  auto args = std::make_shared<SurveyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "survey",
      "Map a hand-laid ceiling (SPEC §8, §10) from one or more recordings of a walk under it (no "
      "ground truth needed): a bundle adjustment (Ceres) of every frame's camera, every marker's "
      "centre and rotation and the camera's tilt (with --intrinsics: the camera's fx, fy, cx, "
      "cy, k1, k2, p1, p2 instead of the tilt). Writes every marker decoded in at least 3 "
      "frames; progress and a summary (RMS reprojection error in px, markers mapped, the "
      "largest corrections in mm and degrees, codes printed twice, parts never seen together) "
      "on stderr. See docs/survey.md.\n"
      "Exit 0 ok, 1 nothing could be mapped or written (says why), 2 usage, 4 malformed "
      "recording, configuration or camera file.");
  cmd->add_option("--replay", args->dirs, "Recording of a walk (repeat for several)")
      ->required()
      ->take_all();
  cmd->add_option("--config", args->config_file,
                  "Configuration (ceiling layout, mount, camera); ceiling.map is not used");
  add_camera_option(cmd, &args->camera_file);
  cmd->add_option("--out", args->out_file, "Map file to write (SPEC §8)")->required();
  auto* intrinsics = cmd->add_flag("--intrinsics", args->intrinsics,
                                   "Also estimate the camera (fx, fy, cx, cy, plumb_bob) from the "
                                   "same frames; needs --camera-out");
  cmd->add_option("--camera-out", args->camera_out_file,
                  "Where --intrinsics writes the camera (ROS camera_info YAML, SPEC §9)")
      ->needs(intrinsics);
  intrinsics->needs(cmd->get_option("--camera-out"));
  cmd->add_option("--mount-out", args->mount_out_file,
                  "Also write the camera's mount (configuration fragment, mount: section) that "
                  "the walk's turns in place and straight runs give; refused (nothing written) "
                  "when the walk has too few of them");
  cmd->add_option("--prior-sigma-mm", args->prior_sigma_mm,
                  "1-sigma of each marker about its nominal spot, mm: how far off a marker may "
                  "be glued")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1000.0));
  cmd->add_option("--threads", args->threads, "Solver threads")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  cmd->callback([args] { run_survey(*args); });
}

const CommandRegistrar kSurveyRegistrar{"survey", &add_survey_command};

}  // namespace
}  // namespace ceilpose::ctl
