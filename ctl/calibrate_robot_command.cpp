// ceilposectl calibrate robot (SPEC §10): one more robot commissioned under a
// surveyed ceiling from one ordinary drive. The camera (fx, fy, k1, k2, the
// principal point, the tilt) comes from a Ceres adjustment of every frame's
// camera against the map's markers (survey/ with a known map); the mount
// from the adjusted camera track's turns in place and straight runs
// (calibration/mount_estimate).
// What the drive cannot tell apart (a principal point off-centre and the
// mount offset; the lens height and the focal length) is held and folded
// into what is estimated, exact for localization, and said so.
#include "ctl/calibrate_robot_command.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "calibration/camera_info_file.h"
#include "calibration/mount_estimate.h"
#include "calibration/mount_fragment.h"
#include "core/output_guard.h"
#include "core/units.h"
#include "ctl/calibration_options.h"
#include "ctl/command_registry.h"
#include "ctl/survey_frames.h"
#include "survey/bundle_adjustment.h"

namespace ceilpose::ctl {
namespace {

// The camera model must explain the image points about as well as the
// detector measures them (0.04-0.07 px on the simulated drives): a fit worse
// than this is a camera the model (p1, p2, k3 held) cannot describe, or a
// map of another ceiling.
constexpr double kMaxFitRmsPx = 0.6;
// Focal lengths known worse than this (relative 1-sigma) are not a
// calibration.
constexpr double kMaxCeilingFocalSigma = 0.002;
constexpr int kMaxDecodePasses = 4;
// A principal point known no better than this was held by its prior about
// the declared one (the lens distorts too little to show its centre).
constexpr double kHeldPrincipalPointSigmaPx = 10.0;

struct RobotArgs {
  std::string dir, config_file, camera_file, map_file, camera_out, mount_out;
  double max_offset_m = MountEstimateOptions{}.max_offset_m;
  int threads = 1;
};

// Decodes the drive with `camera` (null: the declared one) and adjusts the
// camera against the map; the principal point's prior stays about
// *declared (set on the first call).
Result<SurveyReport> adjust_camera(const RobotArgs& args, const FrameSources& sources,
                                   const CameraIntrinsics* camera, CameraIntrinsics* declared,
                                   PipelineConfig* config, std::vector<SurveyFrame>* frames,
                                   int* rc) {
  *rc = collect_survey_frames(sources, "calibrate robot", camera, config, frames);
  if (camera == nullptr) *declared = config->intrinsics;
  if (*rc != kExitOk) return make_error("");  // collect_survey_frames printed why
  if (!config->map) {
    *rc = kExitUsage;
    return make_error("--map is needed: the ceiling's surveyed map (`ceilposectl survey`)");
  }
  SurveyOptions options;
  options.known_map = config->map.get();
  options.declared_camera = declared;
  // A camera far from the declared one gives few frames a pose on the first
  // pass (3 of 300 for k1 -0.22 declared 0): enough to find a camera that
  // localizes the rest, which the later passes must then see from many
  // places.
  if (camera == nullptr) options.min_viewpoints = 1;
  options.estimate_intrinsics = true;
  options.threads = args.threads;
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  options.progress = [tty](const std::string& line) {
    if (tty) std::fprintf(stderr, "\rcalibrate robot: %s   ", line.c_str());
  };
  auto report = survey_ceiling(*config, *frames, options);
  if (tty) std::fputc('\n', stderr);
  *rc = report ? kExitOk : kExitFailure;
  return report;
}

std::string refusal_figures(const char* format, double a, double b) {
  char t[256];
  std::snprintf(t, sizeof t, format, a, b);
  return t;
}

void run_calibrate_robot(const RobotArgs& args) {
  constexpr const char* kCmd = "ceilposectl calibrate robot";
  if (auto clash = check_outputs_are_not_inputs(
          {{"--camera-out", args.camera_out}, {"--mount-out", args.mount_out}},
          {{"--config", args.config_file},
           {"--camera", args.camera_file},
           {"--map", args.map_file}},
          {{"--replay", args.dir}});
      !clash) {
    std::fprintf(stderr, "%s: %s\n", kCmd, clash.error().message.c_str());
    return set_exit_code(kExitUsage);
  }
  FrameSources sources;
  sources.dirs = {args.dir};
  sources.config_file = args.config_file;
  sources.calibration.camera_file = args.camera_file;
  sources.calibration.map_file = args.map_file;
  sources.use_map = true;
  sources.zero_mount = true;
  PipelineConfig config;
  CameraIntrinsics declared;
  std::vector<SurveyFrame> frames;
  int rc = kExitOk;
  auto report = adjust_camera(args, sources, nullptr, &declared, &config, &frames, &rc);
  // The detector corrects its centroids for the distortion it is told of,
  // and frames of a camera far from the declared one localize badly: decode
  // again with the camera found until the frames with a pose stop growing
  // (as `survey --intrinsics` does, once).
  for (int pass = 0; pass < kMaxDecodePasses && report; ++pass) {
    const size_t before = frames.size();
    const CameraIntrinsics found = report->intrinsics;
    std::fprintf(stderr,
                 "calibrate robot: decoding again with the camera found (fx %.2f, fy %.2f, cx "
                 "%.2f, cy %.2f px, k1 %.4f)\n",
                 found.fx, found.fy, found.cx, found.cy, found.distortion[0]);
    report = adjust_camera(args, sources, &found, &declared, &config, &frames, &rc);
    if (pass > 0 && frames.size() <= before) break;
  }
  if (!report) {
    if (!report.error().message.empty())
      std::fprintf(stderr, "%s: %s\n", kCmd, report.error().message.c_str());
    return set_exit_code(rc);
  }
  const SurveyReport& r = *report;
  const CameraIntrinsics& k = r.intrinsics;
  std::fprintf(stderr,
               "calibrate robot: %d frames, %d marker sightings, %d image points; RMS "
               "reprojection error %.3f px\n",
               r.frames_used, r.sightings, r.points, r.rms_px);

  // The mount from the adjusted camera track.
  std::vector<CameraSample> track;
  for (size_t f = 0; f < frames.size(); ++f)
    if (r.used[f])
      track.push_back(
          {frames[f].timestamp_ns * 1e-9, r.cameras[f][0], r.cameras[f][1], r.cameras[f][2]});
  MountEstimateOptions mount_options;
  mount_options.max_offset_m = args.max_offset_m;
  auto mount = estimate_mount(track, mount_options);
  if (!mount) {
    std::fprintf(stderr, "%s: the mount: %s; nothing was written\n", kCmd,
                 mount.error().message.c_str());
    return set_exit_code(kExitFailure);
  }
  for (const MotionSegment& g : mount->segments)
    std::fprintf(stderr, "  %6.2f-%6.2f s  %-40s %.0f deg, %.2f m\n",
                 track[g.first].t_s - track.front().t_s, track[g.last].t_s - track.front().t_s,
                 to_string(g.kind), g.turned_rad * kDegPerRad, g.length_m);

  std::string refusal;
  if (!(r.rms_px <= kMaxFitRmsPx))
    refusal = refusal_figures(
        "the camera model does not fit the drive: RMS reprojection error %.3f px (limit %.1f "
        "px): a lens needing p1, p2 or k3, or a map of another ceiling",
        r.rms_px, kMaxFitRmsPx);
  else if (!(r.sigma_intrinsics[0] <= kMaxCeilingFocalSigma * k.fx &&
             r.sigma_intrinsics[1] <= kMaxCeilingFocalSigma * k.fy))
    refusal = refusal_figures(
        "the drive does not determine the focal lengths: 1-sigma %.2f and %.2f px: drive "
        "under more of the ceiling",
        r.sigma_intrinsics[0], r.sigma_intrinsics[1]);
  if (!refusal.empty()) {
    std::fprintf(stderr, "%s: %s; nothing was written\n", kCmd, refusal.c_str());
    return set_exit_code(kExitFailure);
  }

  const bool centre_found = r.sigma_intrinsics[4] < kHeldPrincipalPointSigmaPx &&
                            r.sigma_intrinsics[5] < kHeldPrincipalPointSigmaPx;
  std::fprintf(stderr, "calibrate robot: determined by the drive (1-sigma):\n");
  std::fprintf(stderr,
               "  fx %.2f +- %.2f px, fy %.2f +- %.2f px, k1 %.5f +- %.5f, k2 %.5f +- %.5f\n", k.fx,
               r.sigma_intrinsics[0], k.fy, r.sigma_intrinsics[1], k.distortion[0],
               r.sigma_intrinsics[2], k.distortion[1], r.sigma_intrinsics[3]);
  if (centre_found)
    std::fprintf(stderr, "  principal point cx %.2f +- %.2f, cy %.2f +- %.2f px\n", k.cx,
                 r.sigma_intrinsics[4], k.cy, r.sigma_intrinsics[5]);
  std::fprintf(stderr,
               "  mount: camera %.2f +- %.2f mm forward, %.2f +- %.2f mm left of the robot "
               "origin, turned %.3f +- %.3f deg (%d turns in place, %.0f deg; %d straight runs, "
               "%.2f m)\n",
               1000.0 * mount->offset_forward_m, 1000.0 * mount->sigma_forward_m,
               1000.0 * mount->offset_left_m, 1000.0 * mount->sigma_left_m,
               kDegPerRad * mount->yaw_rad, kDegPerRad * mount->sigma_yaw_rad, mount->turn_segments,
               kDegPerRad * mount->turned_rad, mount->straight_segments, mount->driven_m);
  if (mount->backwards_m > 0.0)
    std::fprintf(stderr, "  (%.2f m of the straight runs went backwards: taken as reversing)\n",
                 mount->backwards_m);
  std::fprintf(stderr, "calibrate robot: not determined by the drive:\n");
  if (!centre_found)
    std::fprintf(stderr,
                 "  the principal point: cx %.2f, cy %.2f px, held near the declared %.2f, "
                 "%.2f px (the lens distorts too little to show its centre): one off-centre "
                 "cannot be told from a camera mounted off-centre, and the mount offset above "
                 "absorbs it\n",
                 k.cx, k.cy, declared.cx, declared.cy);
  std::fprintf(stderr,
               "  the camera tilt apart from the mount offset: %.3f deg about x, %.3f deg about "
               "y (+- %.3f, %.3f deg) found; a tilt moves the view as an offset does, and the "
               "offset absorbs what the tilt does not\n"
               "  the lens height, held at %.4f m (the configuration's): the focal lengths "
               "absorb an error in it\n"
               "  p1 %.6f, p2 %.6f, k3 %.5f, held at the declared camera's\n"
               "  these files are exact for localization together (--camera with --config of "
               "this mount), not apart\n",
               kDegPerRad * r.tilt_x_rad, kDegPerRad * r.tilt_y_rad,
               kDegPerRad * r.sigma_tilt_rad[0], kDegPerRad * r.sigma_tilt_rad[1],
               config.mount.lens_height_m, k.distortion[2], k.distortion[3], k.distortion[4]);

  const std::string camera_comment =
      "# ceilposectl calibrate robot --replay " + args.dir + " --map " + args.map_file +
      "\n# fx, fy, k1, k2, cx, cy estimated (cx, cy only as far as the lens distortion shows "
      "them); p1, p2, k3 held. Use with the mount in " +
      args.mount_out + ": its offset absorbs what the principal point and tilt leave.\n";
  if (auto wrote = write_camera_info_file(args.camera_out, k, "ceilpose", camera_comment); !wrote) {
    std::fprintf(stderr, "%s: %s\n", kCmd, wrote.error().message.c_str());
    return set_exit_code(kExitFailure);
  }
  MountFragment fragment =
      fragment_of(*mount, config.mount,
                  "ceilposectl calibrate robot --replay " + args.dir + " --map " + args.map_file +
                      "\nUse with the camera in " + args.camera_out +
                      " (the offset absorbs its principal point's).");
  fragment.mount.tilt_x_rad = r.tilt_x_rad;
  fragment.mount.tilt_y_rad = r.tilt_y_rad;
  fragment.with_tilt_and_height = true;
  fragment.sigma_tilt_rad = r.sigma_tilt_rad;
  if (auto wrote = write_mount_fragment(args.mount_out, fragment); !wrote) {
    std::fprintf(stderr, "%s: %s\n", kCmd, wrote.error().message.c_str());
    return set_exit_code(kExitFailure);
  }
  std::fprintf(stderr,
               "calibrate robot: wrote %s and %s (localize with --map %s --camera %s --config "
               "%s)\n",
               args.camera_out.c_str(), args.mount_out.c_str(), args.map_file.c_str(),
               args.camera_out.c_str(), args.mount_out.c_str());
  set_exit_code(kExitOk);
}

}  // namespace

void add_calibrate_robot_command(CLI::App* calibrate) {
  auto args = std::make_shared<RobotArgs>();
  CLI::App* cmd = calibrate->add_subcommand(
      "robot",
      "Commission one more robot under a surveyed ceiling from one ordinary drive (straight "
      "runs, arcs, at least one turn in place; 360 deg of turning in place and 1 m of straight "
      "drive in total; no checkerboard, no ground truth): its camera (fx, fy, k1, k2, tilt) by a "
      "Ceres adjustment against the map's markers, its mount (offset, mounting yaw) from the "
      "turns in place and straight runs. Prints what the drive determined with 1-sigma and what "
      "it could not (held, and folded into what was estimated); writes the camera (SPEC §9) and "
      "a mount: fragment. Localize with --map MAP --camera CAMERA --config MOUNT.\n"
      "Exit 0 ok, 1 the drive cannot determine the robot or does not fit (says what; nothing "
      "written), 2 usage (also an output that is an input), 4 malformed recording, "
      "configuration, map or camera file.");
  cmd->add_option("--replay", args->dir, "Recording of the drive (SPEC §4)")->required();
  cmd->add_option("--map", args->map_file, "The ceiling's surveyed map (SPEC §8, `survey`)")
      ->required();
  cmd->add_option("--config", args->config_file,
                  "Configuration (ceiling layout, lens height, nominal tilt; its mount offset "
                  "and yaw are what is measured)");
  add_camera_option(cmd, &args->camera_file);
  cmd->add_option("--camera-out", args->camera_out, "camera_info file to write (SPEC §9)")
      ->required();
  cmd->add_option("--mount-out", args->mount_out,
                  "Configuration fragment (mount: section) to write")
      ->required();
  add_max_offset_option(cmd, &args->max_offset_m);
  cmd->add_option("--threads", args->threads, "Solver threads")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  cmd->callback([args] { run_calibrate_robot(*args); });
}

}  // namespace ceilpose::ctl
