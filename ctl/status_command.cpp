// ceilposectl status: the daemon's health from its shared-memory segment —
// state, pid, uptime, frame rate, frames, drops, outages, latency percentiles,
// fix state, source and frames per refusal reason. Exit 0 when the daemon is live, 3 otherwise.
#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <memory>
#include <string>

#include "core/clock.h"
#include "core/refusal.h"
#include "ctl/command_registry.h"
#include "ctl/shm_option.h"
#include "ipc/shm/pose_text.h"
#include "ipc/shm/shm_pose_reader.h"

namespace ceilpose::ctl {
namespace {

struct StatusArgs {
  std::string shm = CEILPOSE_DEFAULT_SHM_NAME;
  bool json = false;
  int64_t stale_ms = 0;  // 0: the daemon's ipc.stale_after_ms, from the segment
};

struct Snapshot {
  Liveness liveness;
  WriterInfo info;
  StatusRecord status{};
  bool has_status = false;
  PoseRecord pose{};
  bool has_pose = false;
  int64_t now_ns = 0;
};

// How long the daemon has run: until now, or until it marked itself stopped
// (its last heartbeat).
int64_t run_ns(const Snapshot& s) {
  const int64_t end_ns =
      s.info.state == WriterState::kStopped ? s.info.heartbeat_mono_ns : s.now_ns;
  return end_ns - s.info.start_mono_ns;
}

// Frames per refusal reason (kNone: frames with a pose), as the daemon counted
// them; a reason newer than this ceilposectl is named by its index.
template <typename Fn>
void for_each_refusal(const StatusRecord& st, Fn&& fn) {
  const uint32_t n = std::min<uint32_t>(st.refusal_count, CEILPOSE_REFUSAL_SLOTS);
  for (uint32_t i = 0; i < n; ++i) {
    const std::string_view name = refusal_name(static_cast<int>(i));
    fn(name == "unknown" ? "reason_" + std::to_string(i) : std::string(name), st.refusals[i]);
  }
}

std::string age_ms_json(bool known, int64_t now_ns, int64_t then_ns) {
  return known ? fixed_text(static_cast<double>(now_ns - then_ns) / 1e6, 1) : "null";
}

void print_json(const StatusArgs& args, const Snapshot& s) {
  const StatusRecord& st = s.status;
  std::string out =
      "{\"shm\":" + json_quote(args.shm) + ",\"state\":" + json_quote(to_string(s.info.state)) +
      ",\"liveness\":" + json_quote(to_string(s.liveness)) +
      ",\"live\":" + (s.liveness == Liveness::kLive ? "true" : "false") +
      ",\"pid\":" + std::to_string(s.info.pid) +
      ",\"generation\":" + std::to_string(s.info.generation) +
      ",\"uptime_s\":" + fixed_text(static_cast<double>(run_ns(s)) / 1e9, 3) +
      ",\"start_real_ns\":" + std::to_string(s.info.start_real_ns) +
      ",\"heartbeat_age_ms\":" + age_ms_json(true, s.now_ns, s.info.heartbeat_mono_ns);
  if (s.has_status) {
    out += ",\"fps\":" + fixed_text(st.fps, 2) + ",\"frames\":" + std::to_string(st.frames) +
           ",\"drops\":" + std::to_string(st.drops) + ",\"skipped\":" + std::to_string(st.skipped) +
           ",\"outages\":" + std::to_string(st.outages) +
           ",\"latency_us\":{\"p50\":" + std::to_string(st.latency_p50_us) +
           ",\"p90\":" + std::to_string(st.latency_p90_us) +
           ",\"p99\":" + std::to_string(st.latency_p99_us) +
           ",\"max\":" + std::to_string(st.latency_max_us) + "}" +
           ",\"fix\":" + json_quote(to_string(static_cast<FixState>(st.fix_state))) +
           ",\"source\":" + json_quote(st.source) +
           ",\"tracked_frames\":" + std::to_string(st.tracked_frames) +
           ",\"full_sweep_frames\":" + std::to_string(st.full_sweep_frames) + ",\"refusals\":{";
    bool first = true;
    for_each_refusal(st, [&](const std::string& name, uint64_t count) {
      if (name == to_string(Refusal::kNone)) return;
      out += (first ? "" : ",") + json_quote(name) + ":" + std::to_string(count);
      first = false;
    });
    out += "}" + std::string(",\"localized\":") +
           std::to_string(st.refusal_count > 0 ? st.refusals[0] : 0) +
           ",\"status_age_ms\":" + age_ms_json(true, s.now_ns, st.updated_mono_ns);
  } else {
    out +=
        ",\"fps\":null,\"frames\":null,\"drops\":null,\"skipped\":null,\"outages\":null,"
        "\"latency_us\":null,\"fix\":null,\"source\":null,\"tracked_frames\":null,"
        "\"full_sweep_frames\":null,\"refusals\":null,"
        "\"localized\":null,\"status_age_ms\":null";
  }
  out += ",\"last_seq\":" + (s.has_pose ? std::to_string(s.pose.seq) : std::string("null")) +
         ",\"last_pose_age_ms\":" + age_ms_json(s.has_pose, s.now_ns, s.pose.publish_mono_ns) + "}";
  std::printf("%s\n", out.c_str());
}

void print_human(const StatusArgs& args, const Snapshot& s) {
  const StatusRecord& st = s.status;
  if (s.info.state == WriterState::kStopped) {
    std::printf("ceilposed on %s: stopped %s ago after running %s, pid %d\n", args.shm.c_str(),
                duration_text(s.now_ns - s.info.heartbeat_mono_ns).c_str(),
                duration_text(run_ns(s)).c_str(), s.info.pid);
  } else {
    std::printf("ceilposed on %s: %s (%s), pid %d, up %s\n", args.shm.c_str(),
                to_string(s.info.state), to_string(s.liveness), s.info.pid,
                duration_text(run_ns(s)).c_str());
  }
  if (s.has_status) {
    std::printf("  source     %s\n", st.source[0] != '\0' ? st.source : "(not reported)");
    std::printf("  fix        %s\n", to_string(static_cast<FixState>(st.fix_state)));
    std::printf("  rate       %.1f fps\n", st.fps);
    std::printf("  frames     %" PRIu64 "  drops %" PRIu64 "  skipped %" PRIu64 "  outages %" PRIu64
                "\n",
                st.frames, st.drops, st.skipped, st.outages);
    std::printf(
        "  latency    p50 %.2f ms  p90 %.2f ms  p99 %.2f ms  max %.2f ms"
        "  (capture -> pose published)\n",
        st.latency_p50_us / 1e3, st.latency_p90_us / 1e3, st.latency_p99_us / 1e3,
        st.latency_max_us / 1e3);
    const double swept = static_cast<double>(st.tracked_frames) + st.full_sweep_frames;
    std::printf("  sweeps     %" PRIu32 " tracked (%.0f %%), %" PRIu32
                " whole  (frames since start; tracked: only where the markers were predicted)\n",
                st.tracked_frames, swept > 0 ? 100.0 * st.tracked_frames / swept : 0.0,
                st.full_sweep_frames);
    std::string refused;
    for_each_refusal(st, [&](const std::string& name, uint64_t count) {
      if (count == 0 || name == to_string(Refusal::kNone)) return;
      refused += (refused.empty() ? "" : ", ") + name + " " + std::to_string(count);
    });
    std::printf("  no pose    %s  (frames per refusal since start)\n",
                refused.empty() ? "none refused" : refused.c_str());
  } else {
    std::printf("  (the daemon has not reported its status yet)\n");
  }
  if (s.has_pose) {
    std::printf("  last pose  %s\n", pose_line(s.pose, s.now_ns).c_str());
  } else {
    std::printf("  last pose  none yet\n");
  }
  std::printf("  heartbeat  %.1f ms ago\n",
              static_cast<double>(s.now_ns - s.info.heartbeat_mono_ns) / 1e6);
}

int run_status(const StatusArgs& args) {
  shm::ShmErrc code = shm::ShmErrc::kOk;
  auto reader = ShmPoseReader::open(args.shm, &code);
  if (!reader) {
    std::fprintf(stderr, "ceilposectl status: %s\n", reader.error().message.c_str());
    if (args.json) {
      std::printf("{\"shm\":%s,\"state\":null,\"liveness\":\"none\",\"live\":false,\"error\":%s}\n",
                  json_quote(args.shm).c_str(), json_quote(reader.error().message).c_str());
    }
    const bool no_daemon = code == shm::ShmErrc::kNotFound || code == shm::ShmErrc::kNotReady;
    return no_daemon ? kExitNoDaemon : kExitFailure;
  }
  Snapshot s;
  s.liveness = reader->liveness(args.stale_ms);
  s.info = reader->writer_info();
  s.has_status = reader->read_status(&s.status) == ReadResult::kOk && s.status.updated_mono_ns != 0;
  s.has_pose = reader->read_latest(&s.pose) == ReadResult::kOk;
  s.now_ns = monotonic_ns();
  if (args.json) {
    print_json(args, s);
  } else {
    print_human(args, s);
  }
  if (s.liveness == Liveness::kLive || s.liveness == Liveness::kStarting) return kExitOk;
  std::fprintf(stderr, "ceilposectl status: daemon on %s is %s%s\n", args.shm.c_str(),
               to_string(s.liveness),
               s.liveness == Liveness::kRestarted ? " (a new daemon took over; run again)" : "");
  return kExitNoDaemon;
}

void add_status_command(CLI::App& app) {
  auto args = std::make_shared<StatusArgs>();
  CLI::App* cmd = app.add_subcommand(
      "status",
      "Show the daemon's health from its shared memory: state, pid, uptime, fps, frames, drops, "
      "skipped, outages, latency percentiles, fix state, source, and frames per refusal reason "
      "(--json: an object \"refusals\" of reason -> count, \"localized\" the frames with a pose). "
      "Exit 0 when the daemon is live "
      "(or starting), 3 when none is publishing or it stopped, died or is stale.");
  add_shm_option(cmd, &args->shm);
  cmd->add_flag("--json", args->json, "one JSON object for scripts");
  cmd->add_option("--stale-ms", args->stale_ms,
                  "a heartbeat older than this is stale"
                  " (default: the daemon's ipc.stale_after_ms, published in the segment)")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([args] {
    const int rc = run_status(*args);
    std::fflush(stdout);
    set_exit_code(rc);
  });
}

const CommandRegistrar kStatusRegistrar{"status", &add_status_command};

}  // namespace
}  // namespace ceilpose::ctl
