// ceilposectl evaluate: localizes a recording like `locate` and scores it
// against the recording's ground truth with the metrics of SPEC §6.
#include <cstdio>

#include "ctl/command_registry.h"
#include "ctl/replay_run.h"
#include "pipeline/accuracy_metrics.h"
#include "pipeline/motion_metrics.h"
#include "sim/visibility.h"

namespace ceilpose::ctl {
namespace {

void print_report(const AccuracyReport& r, bool json) {
  if (json) {
    std::printf(
        "{\"frames\":%d,\"frames_with_whole\":%d,\"valid_with_whole\":%d,"
        "\"valid_without_whole\":%d,\"availability\":%.6f,\"within_both\":%.6f,"
        "\"within_x\":%.6f,\"within_y\":%.6f,\"median_error_mm\":%.4f,\"p99_error_mm\":%.4f,"
        "\"max_error_mm\":%.4f,\"yaw_p99_deg\":%.4f,\"yaw_max_deg\":%.4f,\"gross\":%d,"
        "\"mean_nees\":%.4f,\"median_nees\":%.4f,"
        "\"modes\":{\"axes\":%d,\"barycentric\":%d,\"lsq\":%d}",
        r.frames, r.frames_with_whole, r.valid_with_whole, r.valid_without_whole, r.availability,
        r.within_both, r.within_x, r.within_y, r.median_error_mm, r.p99_error_mm, r.max_error_mm,
        r.yaw_p99_deg, r.yaw_max_deg, r.gross, r.mean_nees, r.median_nees, r.mode_count[1],
        r.mode_count[2], r.mode_count[3]);
    return;
  }
  std::printf("frames with ground truth      %d\n", r.frames);
  std::printf("availability                  %.2f%% (%d of %d frames with a whole marker)\n",
              100.0 * r.availability, r.valid_with_whole, r.frames_with_whole);
  std::printf("valid without a whole marker  %d\n", r.valid_without_whole);
  std::printf("|dx|,|dy| <= 0.05 grid units  %.2f%% both, %.2f%% x, %.2f%% y\n",
              100.0 * r.within_both, 100.0 * r.within_x, 100.0 * r.within_y);
  std::printf("position error                median %.2f mm, p99 %.2f mm, max %.2f mm\n",
              r.median_error_mm, r.p99_error_mm, r.max_error_mm);
  std::printf("yaw error                     p99 %.3f deg, max %.3f deg\n", r.yaw_p99_deg,
              r.yaw_max_deg);
  std::printf("gross errors                  %d\n", r.gross);
  std::printf("NEES (x, y, yaw)              mean %.2f, median %.2f (3 = honest covariance)\n",
              r.mean_nees, r.median_nees);
  std::printf("modes used                    axes %d, barycentric %d, lsq %d\n", r.mode_count[1],
              r.mode_count[2], r.mode_count[3]);
}

// Text lines or JSON members (no braces) for the filtered run's motion.
void print_motion(const MotionReport& m, bool json) {
  if (json) {
    std::printf(
        ",\"motion\":{\"frames\":%d,\"median_error_mm\":%.4f,\"p99_error_mm\":%.4f,"
        "\"max_error_mm\":%.4f,\"yaw_p99_deg\":%.4f,\"velocity_frames\":%d,"
        "\"velocity_median_error_mps\":%.5f,"
        "\"velocity_p99_error_mps\":%.5f,\"yaw_rate_median_error_radps\":%.5f,"
        "\"predict_ms\":%.3f,\"predicted_frames\":%d,\"predicted_median_error_mm\":%.4f,"
        "\"predicted_p99_error_mm\":%.4f,\"predicted_max_error_mm\":%.4f,"
        "\"predicted_yaw_p99_deg\":%.4f,\"unpredicted_p99_error_mm\":%.4f}",
        m.frames, m.median_error_mm, m.p99_error_mm, m.max_error_mm, m.yaw_p99_deg,
        m.velocity_frames, m.velocity_median_error_mps, m.velocity_p99_error_mps,
        m.yaw_rate_median_error_radps, m.predict_ms, m.predicted_frames,
        m.predicted_median_error_mm, m.predicted_p99_error_mm, m.predicted_max_error_mm,
        m.predicted_yaw_p99_deg, m.unpredicted_p99_error_mm);
    return;
  }
  std::printf(
      "filtered pose at frame time   median %.2f mm, p99 %.2f mm, max %.2f mm (%d frames)\n",
      m.median_error_mm, m.p99_error_mm, m.max_error_mm, m.frames);
  std::printf(
      "velocity error                median %.4f m/s, p99 %.4f m/s; yaw rate median "
      "%.4f rad/s\n",
      m.velocity_median_error_mps, m.velocity_p99_error_mps, m.yaw_rate_median_error_radps);
  std::printf(
      "predicted %.1f ms ahead        median %.2f mm, p99 %.2f mm, max %.2f mm, yaw p99 "
      "%.3f deg (unpredicted: p99 %.2f mm)\n",
      m.predict_ms, m.predicted_median_error_mm, m.predicted_p99_error_mm, m.predicted_max_error_mm,
      m.predicted_yaw_p99_deg, m.unpredicted_p99_error_mm);
}

void add_evaluate_command(CLI::App& app) {
  auto args = std::make_shared<ReplayArgs>();
  auto json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "evaluate",
      "Localize a recording (as `locate`) and score it against its ground-truth columns with "
      "SPEC §6's metrics: availability among frames with a whole marker in view (computed from "
      "the ground truth, the configured mount and layout and the recording's camera), share "
      "within 0.05 grid units on both axes, median/p99 position error, yaw p99, gross errors. "
      "With --filter or --predict-ms MS (default 66.667 with --filter) also how the filter "
      "follows the motion: pose at frame time, velocity against the ground truth's central "
      "differences, and the pose predicted MS ahead against the truth at that instant. Exit 4 when "
      "the recording is malformed or has no ground truth.");
  add_replay_options(cmd, args.get());
  cmd->add_flag("--json", *json, "One JSON object instead of the text summary");
  cmd->callback([args, json] {
    ReplaySetup setup;
    int rc = prepare_replay(*args, "evaluate", &setup);
    if (rc == kExitOk && !setup.reader->has_ground_truth_columns()) {
      std::fprintf(stderr,
                   "ceilposectl evaluate: %s/frames.csv: no ground-truth columns "
                   "(gt_x_m, gt_y_m, gt_yaw_rad)\n",
                   args->dir.c_str());
      rc = kExitBadInput;
    }
    const sim::SceneOptions scene{setup.config.layout, setup.config.intrinsics, 1, nullptr};
    AccuracySink accuracy(setup.config.layout.grid_m, [&](const Pose2D& truth) {
      return sim::count_whole_markers(scene, truth, setup.config.mount) > 0;
    });
    // Two frames at 30 fps: the age of a pose when a controller reads it (docs/latency.md).
    MotionAccuracySink motion(args->predict_ms.value_or(66.667));
    const bool filtered = setup.config.filter.enabled;
    if (rc == kExitOk) {
      PoseSink* sinks[] = {&accuracy, &motion};
      rc =
          run_replay(*args, "evaluate", setup, std::span<PoseSink* const>(sinks, filtered ? 2 : 1));
    }
    if (rc == kExitOk) {
      print_report(accuracy.report(), *json);
      if (filtered) print_motion(motion.report(), *json);
      if (*json) std::fputs("}\n", stdout);
    }
    std::fflush(stdout);
    set_exit_code(rc);
  });
}

const CommandRegistrar kEvaluateRegistrar{"evaluate", &add_evaluate_command};

}  // namespace
}  // namespace ceilpose::ctl
