// ceilposectl pose: the latest pose from the daemon's shared-memory segment.
// Exit 0 with a live pose; 3 (kExitNoDaemon) when no daemon publishes on the
// segment or its pose is stale, saying which on stderr.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "core/clock.h"
#include "ctl/command_registry.h"
#include "ctl/shm_option.h"
#include "ipc/shm/pose_text.h"
#include "ipc/shm/shm_pose_reader.h"

namespace ceilpose::ctl {
namespace {

struct PoseArgs {
  std::string shm = CEILPOSE_DEFAULT_SHM_NAME;
  bool json = false;
  int64_t stale_ms = 0;  // 0: the daemon's ipc.stale_after_ms, from the segment
  std::string at;        // --at: "now" or "+MS"; empty: the frame's own pose
};

// --at's instant on CLOCK_MONOTONIC: now, or MS milliseconds after now.
bool parse_at(const std::string& text, int64_t now_ns, int64_t* at_ns) {
  if (text == "now") {
    *at_ns = now_ns;
    return true;
  }
  if (text.size() < 2 || text[0] != '+') return false;
  char* end = nullptr;
  const double ms = std::strtod(text.c_str() + 1, &end);
  if (end == text.c_str() + 1 || *end != '\0' || !(ms >= 0.0 && ms <= 10000.0)) return false;
  *at_ns = now_ns + std::llround(ms * 1e6);
  return true;
}

int report_no_pose(const PoseArgs& args, const std::string& daemon, const std::string& why) {
  if (args.json) {
    std::printf("%s\n", no_pose_json(",\"daemon\":" + json_quote(daemon)).c_str());
  }
  std::fprintf(stderr, "ceilposectl pose: %s\n", why.c_str());
  return kExitNoDaemon;
}

int run_pose(const PoseArgs& args) {
  shm::ShmErrc code = shm::ShmErrc::kOk;
  auto reader = ShmPoseReader::open(args.shm, &code);
  if (!reader) {
    if (code == shm::ShmErrc::kNotFound || code == shm::ShmErrc::kNotReady) {
      return report_no_pose(args, "none", "no daemon publishing: " + reader.error().message);
    }
    std::fprintf(stderr, "ceilposectl pose: %s\n", reader.error().message.c_str());
    return kExitFailure;
  }
  const Liveness liveness = reader->liveness(args.stale_ms);
  const WriterInfo info = reader->writer_info();
  PoseRecord pose{};
  const ReadResult read = reader->read_latest(&pose);
  const int64_t now_ns = monotonic_ns();
  if (read == ReadResult::kNoPose) {
    return report_no_pose(args, to_string(liveness),
                          "ceilposed (pid " + std::to_string(info.pid) + ") on " + args.shm +
                              " is " + to_string(liveness) + " and has published no pose yet");
  }
  if (read == ReadResult::kBusy) {
    std::fprintf(stderr, "ceilposectl pose: %s on %s\n", to_string(read), args.shm.c_str());
    return kExitFailure;
  }
  const double age_ms = static_cast<double>(now_ns - pose.publish_mono_ns) / 1e6;
  std::string predicted;  // JSON members for --at
  if (!args.at.empty()) {
    int64_t at_ns = 0;
    parse_at(args.at, now_ns, &at_ns);  // checked by the option's validator
    PoseRecord ahead{};
    const PredictResult r = predict_pose(pose, at_ns, &ahead);
    const double ahead_ms = static_cast<double>(at_ns - pose.capture_mono_ns) / 1e6;
    if (r != PredictResult::kOk) {
      std::fprintf(stderr, "ceilposectl pose: --at %s: %s\n", args.at.c_str(),
                   r == PredictResult::kNoMotion
                       ? "the latest pose is invalid or unfiltered: nothing to predict from"
                       : ("the instant is " + fixed_text(ahead_ms, 1) +
                          " ms from the frame, beyond the daemon's predict horizon of " +
                          std::to_string(pose.predict_horizon_ms) + " ms")
                             .c_str());
      return kExitFailure;
    }
    pose = ahead;
    predicted = ",\"predicted_mono_ns\":" + std::to_string(at_ns) +
                ",\"predict_ms\":" + fixed_text(ahead_ms, 3);
  }
  std::string problem;
  if (liveness != Liveness::kLive) {
    problem = "daemon (pid " + std::to_string(info.pid) + ") on " + args.shm + " is " +
              to_string(liveness) + "; last pose is " + fixed_text(age_ms, 1) + " ms old";
  } else if (const int64_t limit_ms = reader->stale_after_ms(args.stale_ms);
             age_ms > static_cast<double>(limit_ms)) {
    problem = "pose is stale: " + fixed_text(age_ms, 1) + " ms old (limit " +
              std::to_string(limit_ms) + " ms), daemon pid " + std::to_string(info.pid) +
              " is alive but not publishing";
  }
  const std::string daemon = problem.empty() || liveness != Liveness::kLive
                                 ? to_string(liveness)
                                 : std::string("stale-pose");
  if (args.json) {
    std::printf("%s\n", pose_json(pose, now_ns,
                                  predicted + ",\"daemon\":" + json_quote(daemon) +
                                      ",\"live\":" + (problem.empty() ? "true" : "false"))
                            .c_str());
  } else {
    std::printf("%s%s\n", pose_line(pose, now_ns).c_str(),
                args.at.empty() ? "" : ("  (predicted to --at " + args.at + ")").c_str());
  }
  if (!problem.empty()) {
    std::fprintf(stderr, "ceilposectl pose: %s\n", problem.c_str());
    return kExitNoDaemon;
  }
  return kExitOk;
}

void add_pose_command(CLI::App& app) {
  auto args = std::make_shared<PoseArgs>();
  CLI::App* cmd = app.add_subcommand(
      "pose",
      "Print the latest pose from the daemon's shared memory. Exit 0 with a live pose; 3 when "
      "no daemon is publishing, it stopped or died, or its pose is stale (stderr says which). "
      "--json prints seq, valid, x_m, y_m, yaw_rad (null when invalid), mode, markers, "
      "timestamp_ns (capture, CLOCK_MONOTONIC), with the filter vx_mps, vy_mps, yaw_rate_radps, "
      "and more, plus daemon and live. --at predicts the pose to now or MS ms from now with the "
      "filter's motion (exit 1 beyond the daemon's filter.predict_horizon_ms).");
  add_shm_option(cmd, &args->shm);
  cmd->add_flag("--json", args->json, "one JSON object for scripts");
  cmd->add_option("--stale-ms", args->stale_ms,
                  "a pose or heartbeat older than this is stale"
                  " (default: the daemon's ipc.stale_after_ms, published in the segment)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--at", args->at,
                  "now | +MS: the pose where the robot is now, or MS milliseconds from now, "
                  "predicted from the latest frame (ceilpose_client_predict)")
      ->check([](const std::string& text) {
        int64_t at_ns = 0;
        return parse_at(text, 0, &at_ns) ? std::string()
                                         : std::string("expected now or +MS (0 <= MS <= 10000)");
      });
  cmd->callback([args] {
    const int rc = run_pose(*args);
    std::fflush(stdout);
    set_exit_code(rc);
  });
}

const CommandRegistrar kPoseRegistrar{"pose", &add_pose_command};

}  // namespace
}  // namespace ceilpose::ctl
