// ceilposectl locate: localizes every frame of a recording and prints one
// JSON object per frame (SPEC §5).
#include <sys/stat.h>

#include <array>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <vector>

#include "core/json_text.h"
#include "ctl/annotate_sink.h"
#include "ctl/command_registry.h"
#include "ctl/replay_run.h"

namespace ceilpose::ctl {
namespace {

// One JSON object per frame (SPEC §5). Metres and radians to 0.1 µm /
// 0.1 µrad: far below the accuracy, so the output never hides a difference
// the estimate makes.
class JsonLinesSink final : public PoseSink {
 public:
  JsonLinesSink(PositioningMode requested, std::optional<double> predict_ms)
      : requested_(requested), predict_ms_(predict_ms) {}

  void consume(const Localization& loc) override {
    const PoseEstimate& e = loc.published;
    const int64_t proc_us = (loc.localize_ns + 500) / 1000;
    // An invalid frame names the mode that was asked for: none was used.
    const std::string_view mode = to_string(e.valid ? e.mode : requested_);
    const char* sweep = loc.tracked() ? "tracked" : "full";
    if (e.valid) {
      Pose2D pose = e.pose;
      std::array<double, 9> cov = e.covariance;
      MotionState motion = loc.motion.state;
      if (loc.motion.valid && predict_ms_) {
        motion = motion_at(loc.motion, loc.frame.timestamp_ns + std::llround(*predict_ms_ * 1e6));
        pose = {motion.x[0], motion.x[1], motion.x[2]};
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) cov[r * 3 + c] = motion.p[r * kMotionStates + c];
      }
      std::printf("{\"index\":%" PRId64 ",\"timestamp_ns\":%" PRId64
                  ",\"valid\":true%s"
                  ",\"mode\":\"%.*s\",\"markers\":%d,\"proc_us\":%" PRId64
                  ",\"sweep\":\"%s\",\"refusal\":null,\"rms_px\":%.3f,"
                  "\"cov\":[%.3e,%.3e,%.3e,%.3e,%.3e,%.3e]",
                  loc.frame.index, loc.frame.timestamp_ns, pose_fields_json(&pose).c_str(),
                  static_cast<int>(mode.size()), mode.data(), e.markers, proc_us, sweep,
                  e.rms_residual_px, cov[0], cov[1], cov[2], cov[4], cov[5], cov[8]);
      if (loc.motion.valid)
        std::printf(",\"vx_mps\":%.6f,\"vy_mps\":%.6f,\"yaw_rate_radps\":%.6f", motion.x[3],
                    motion.x[4], motion.x[5]);
      if (predict_ms_) std::printf(",\"predict_ms\":%.3f", *predict_ms_);
      std::fputs("}\n", stdout);
    } else {
      const std::string_view refusal = to_string(e.refusal);
      std::printf("{\"index\":%" PRId64 ",\"timestamp_ns\":%" PRId64
                  ",\"valid\":false%s"
                  ",\"mode\":\"%.*s\",\"markers\":%d,\"proc_us\":%" PRId64
                  ",\"sweep\":\"%s\",\"refusal\":\"%.*s\"",
                  loc.frame.index, loc.frame.timestamp_ns, pose_fields_json(nullptr).c_str(),
                  static_cast<int>(mode.size()), mode.data(), e.markers, proc_us, sweep,
                  static_cast<int>(refusal.size()), refusal.data());
      if (predict_ms_) std::printf(",\"predict_ms\":%.3f", *predict_ms_);
      std::fputs("}\n", stdout);
    }
  }

 private:
  PositioningMode requested_;
  std::optional<double> predict_ms_;
};

void add_locate_command(CLI::App& app) {
  auto args = std::make_shared<ReplayArgs>();
  auto annotate_dir = std::make_shared<std::string>();
  auto annotate_refused = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "locate",
      "Localize every frame of a recording in order, as fast as possible; one JSON object per "
      "frame on stdout (SPEC §5): index, timestamp_ns, valid, x_m, y_m, yaw_rad (null when "
      "invalid), mode, markers, proc_us, sweep (\"tracked\": with --filter's fix only the "
      "windows where the markers were predicted were swept; \"full\": the whole frame), refusal "
      "(why an invalid frame has no pose, e.g. "
      "no_markers, wrong_heights; null when valid), and for valid frames rms_px and cov (the "
      "upper triangle of the (x, y, yaw) covariance: xx, xy, xyaw, yy, yyaw, yawyaw); with "
      "--filter also vx_mps, vy_mps (world frame) and yaw_rate_radps, with --predict-ms MS the "
      "pose, covariance and velocity predicted MS ms past the frame and predict_ms. Errors "
      "on stderr; exit 4 for a malformed recording or configuration, 2 for usage.");
  add_replay_options(cmd, args.get());
  cmd->add_option("--annotate", *annotate_dir,
                  "Also write DIR/frame_NNNNNN.png per frame: every rectangle candidate (grey), "
                  "each red/green pair with its code (green) or why it was rejected (orange), "
                  "the pose or the refusal");
  cmd->add_flag("--annotate-refused", *annotate_refused,
                "With --annotate: only the frames without a pose");
  cmd->callback([args, annotate_dir, annotate_refused] {
    ReplaySetup setup;
    int rc = prepare_replay(*args, "locate", &setup);
    if (rc == kExitOk) {
      JsonLinesSink out(setup.config.positioning.mode, args->predict_ms);
      AnnotateSink annotate(*annotate_dir, *annotate_refused);
      std::vector<PoseSink*> sinks{&out};
      if (!annotate_dir->empty()) {
        if (::mkdir(annotate_dir->c_str(), 0755) != 0 && errno != EEXIST) {
          std::fprintf(stderr, "ceilposectl locate: --annotate %s: cannot create: %s\n",
                       annotate_dir->c_str(), std::strerror(errno));
          return set_exit_code(kExitFailure);
        }
        sinks.push_back(&annotate);
      }
      rc = run_replay(*args, "locate", setup, sinks);
      if (rc == kExitOk && !annotate.error().empty()) {
        std::fprintf(stderr, "ceilposectl locate: %s\n", annotate.error().c_str());
        rc = kExitFailure;
      } else if (rc == kExitOk && !annotate_dir->empty()) {
        std::fprintf(stderr, "locate: wrote %d annotated frames to %s\n", annotate.written(),
                     annotate_dir->c_str());
      }
    }
    std::fflush(stdout);
    set_exit_code(rc);
  });
}

const CommandRegistrar kLocateRegistrar{"locate", &add_locate_command};

}  // namespace
}  // namespace ceilpose::ctl
