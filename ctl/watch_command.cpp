// ceilposectl watch: streams poses as the daemon publishes them (blocking on
// the segment's futex, no polling): a table for people, JSON lines with
// --json. Waits for a daemon that is not running yet and follows a restart by
// re-attaching to the new segment.
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <thread>

#include "config/cli_checks.h"
#include "core/clock.h"
#include "ctl/command_registry.h"
#include "ctl/shm_option.h"
#include "ipc/shm/pose_text.h"
#include "ipc/shm/shm_pose_reader.h"

namespace ceilpose::ctl {
namespace {

struct WatchArgs {
  std::string shm = CEILPOSE_DEFAULT_SHM_NAME;
  bool json = false;
  uint64_t count = 0;    // 0: until interrupted
  int64_t stale_ms = 0;  // 0: the daemon's ipc.stale_after_ms, from the segment
};

// How long one wait lasts before the reader re-checks for a restart.
constexpr int kWaitSliceMs = 500;
// After a stop or death, how often to look for the daemon's successor.
constexpr auto kSuccessorCheck = std::chrono::milliseconds(100);
constexpr int kHeaderEveryRows = 40;

void note(const std::string& text) {
  std::fprintf(stderr, "ceilposectl watch: %s\n", text.c_str());
}

Result<ShmPoseReader> attach(const WatchArgs& args, shm::ShmErrc* code) {
  auto reader = ShmPoseReader::open(args.shm, code);
  if (reader || (*code != shm::ShmErrc::kNotFound && *code != shm::ShmErrc::kNotReady)) {
    return reader;
  }
  note(reader.error().message + "; waiting for ceilposed to start");
  return ShmPoseReader::open_waiting(args.shm, -1, code);
}

int run_watch(const WatchArgs& args) {
  shm::ShmErrc code = shm::ShmErrc::kOk;
  auto opened = attach(args, &code);
  if (!opened) {
    note(opened.error().message);
    return kExitFailure;
  }
  ShmPoseReader reader = std::move(opened.value());
  const bool tty = ::isatty(STDOUT_FILENO) != 0;
  uint64_t last_seq = 0;
  uint64_t printed = 0;
  std::string reported;  // the last liveness problem told to the user
  uint64_t skipped = 0;  // poses published but never printed (seq gaps)
  int busy_in_a_row = 0;
  while (args.count == 0 || printed < args.count) {
    PoseRecord pose;
    const WaitResult r = reader.wait_next(last_seq, kWaitSliceMs, &pose);
    if (r == WaitResult::kPose) {
      busy_in_a_row = 0;
      if (pose.seq == last_seq) {  // a header written over points at the pose already printed
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        continue;
      }
      // The first pose after attaching is the segment's latest, however old:
      // a stopped, dead or stale daemon's last pose is not a pose to print
      // as current (issue 28: watch --count 1 printed a killed daemon's pose,
      // valid, 6 s old, and exited 0). Say so and wait for a live one.
      if (last_seq == 0) {
        const Liveness now = reader.liveness(args.stale_ms);
        if (now == Liveness::kStopped || now == Liveness::kWriterDead || now == Liveness::kStale) {
          note("daemon (pid " + std::to_string(reader.writer_info().pid) + ") on " + args.shm +
               " is " + std::string(to_string(now)) + "; its last pose (seq " +
               std::to_string(pose.seq) + ") is not shown; waiting");
          reported = to_string(now);
          last_seq = pose.seq;
          continue;
        }
      }
      if (last_seq != 0 && pose.seq < last_seq) {
        note("pose sequence on " + args.shm + " went back from " + std::to_string(last_seq) +
             " to " + std::to_string(pose.seq) +
             " without a restart: something other than ceilposed wrote into the segment");
      } else if (last_seq != 0 && pose.seq > last_seq + 1) {
        // Said when it starts and then every 100 lost, not per pose.
        const uint64_t gap = pose.seq - last_seq - 1;
        if (skipped == 0 || skipped / 100 != (skipped + gap) / 100) {
          note("skipped " + std::to_string(skipped + gap) + " pose(s) so far (last gap: seq " +
               std::to_string(last_seq + 1) + " to " + std::to_string(pose.seq - 1) +
               "): poses were published faster than they were printed");
        }
        skipped += gap;
      }
      const int64_t now_ns = monotonic_ns();
      if (args.json) {
        std::printf("%s\n", pose_json(pose, now_ns).c_str());
      } else {
        if (printed == 0 || (tty && printed % kHeaderEveryRows == 0)) {
          std::printf("%s\n", pose_table_header().c_str());
        }
        std::printf("%s\n", pose_table_row(pose, now_ns).c_str());
      }
      if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
        note(std::string("cannot write to stdout: ") + std::strerror(errno) + " after " +
             std::to_string(printed) + " poses");
        return kExitFailure;
      }
      last_seq = pose.seq;
      ++printed;
      reported.clear();
      continue;
    }
    if (r == WaitResult::kBusy) {
      // The writer never holds a slot this long; garbage over the segment
      // does, until the writer's next publish overwrites it.
      if (++busy_in_a_row == 10) {
        note("the latest pose on " + args.shm +
             " stays unreadable (torn): something wrote over the segment; waiting for the "
             "daemon's next pose");
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      continue;
    }
    const Liveness liveness = reader.liveness(args.stale_ms);
    if (liveness == Liveness::kRestarted) {
      shm::ShmErrc reattach_code = shm::ShmErrc::kOk;
      if (reader.reattach(&reattach_code)) {
        note("daemon restarted: re-attached to " + args.shm + " (pid " +
             std::to_string(reader.writer_info().pid) + ")");
        last_seq = 0;  // a new writer counts from 1 again
        reported.clear();
      } else {
        std::this_thread::sleep_for(kSuccessorCheck);  // still initializing
      }
      continue;
    }
    if (liveness != Liveness::kLive && liveness != Liveness::kStarting &&
        reported != to_string(liveness)) {
      reported = to_string(liveness);
      note("daemon (pid " + std::to_string(reader.writer_info().pid) + ") on " + args.shm + " is " +
           reported + "; waiting");
    }
    // wait_next returns at once for a stopped or dead writer.
    if (r != WaitResult::kTimeout) std::this_thread::sleep_for(kSuccessorCheck);
  }
  return kExitOk;
}

void add_watch_command(CLI::App& app) {
  auto args = std::make_shared<WatchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "watch",
      "Stream poses from the daemon's shared memory as they are published: a table for people, "
      "one JSON object per line with --json (seq, valid, x_m, y_m, yaw_rad, mode, markers, "
      "timestamp_ns, ...). Waits for the daemon if it is not running and re-attaches when it "
      "restarts. Exit 0 after --count poses.");
  add_shm_option(cmd, &args->shm);
  cmd->add_flag("--json", args->json, "JSON lines for machines");
  cmd->add_option("--count", args->count, "stop after N poses (0: until interrupted)")
      ->capture_default_str()
      ->check(cli::count());
  cmd->add_option("--stale-ms", args->stale_ms,
                  "a heartbeat older than this is stale"
                  " (default: the daemon's ipc.stale_after_ms, published in the segment)")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([args] {
    const int rc = run_watch(*args);
    std::fflush(stdout);
    set_exit_code(rc);
  });
}

const CommandRegistrar kWatchRegistrar{"watch", &add_watch_command};

}  // namespace
}  // namespace ceilpose::ctl
