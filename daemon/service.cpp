#include "daemon/service.h"

#include <pthread.h>
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>
#include <new>
#include <numbers>
#include <sstream>
#include <string>

#include "capture/capture_thread.h"
#include "capture/frame_source.h"
#include "capture/source_spec.h"
#include "capture/synthetic_source.h"
#include "core/clock.h"
#include "core/exit_codes.h"
#include "daemon/cyclone_log.h"
#include "daemon/dds_pose_sink.h"
#include "daemon/fleet_thread.h"
#include "daemon/logging.h"
#include "daemon/pipeline_worker.h"
#include "daemon/pose_printer.h"
#include "daemon/problem_report.h"
#include "daemon/shm_pose_sink.h"
#include "daemon/signal_channel.h"
#include "daemon/systemd_notifier.h"
#include "daemon/watchdog_gate.h"
#include "ipc/dds/dds_options.h"
#include "ipc/dds/dds_pose_publisher.h"
#include "ipc/shm/shm_pose_writer.h"
#include "keystore/keystore.h"
#include "sim/trajectory_camera.h"

namespace ceilpose::daemon {
namespace {

constexpr int64_t kPrintPeriodNs = 100 * kMsNs;  // --print-poses: at most 10 lines a second
// How soon a queued READY=1/RELOADING=1/STOPPING=1 is offered to systemd again.
constexpr int64_t kQueuedRetryMs = 50;

// What another process (the segment owner's user or root) did to a
// segment, as counted by its writer, when it differs from what was reported.
void report_damage(const std::string& what, const std::string& name, const shm::SegmentDamage& now,
                   shm::SegmentDamage* reported) {
  if (now.truncations != reported->truncations)
    spdlog::error(
        "shared memory: {} was truncated by another process (its owner's user or root); grown "
        "back to its size, {} times so far; readers re-attach",
        what, now.truncations);
  if (now.header_repairs != reported->header_repairs)
    spdlog::error(
        "shared memory: the header of {} was overwritten by another process (its owner's "
        "user or root); restored, {} times so far",
        name, now.header_repairs);
  *reported = now;
}

// The configured source options at the calibrated frame size.
capture::SourceOptions source_options(const ServiceConfig& c) {
  capture::SourceOptions o = c.capture.device;
  o.width = c.pipeline.intrinsics.width;
  o.height = c.pipeline.intrinsics.height;
  o.readout_ms = c.pipeline.intrinsics.readout_ms;
  return o;
}

// The synthetic camera shows the configured ceiling through the configured
// camera and mount; other sources need no generator.
std::shared_ptr<FrameGenerator> frame_generator(const ServiceConfig& c) {
  if (!capture::is_synthetic_spec(c.capture.source)) return nullptr;
  sim::TrajectoryCameraOptions o;
  o.scene = sim::SceneOptions{c.pipeline.layout, c.pipeline.intrinsics, c.capture.synthetic_seed,
                              nullptr};
  o.mount = c.pipeline.mount;
  // check_config refused a format the synthetic camera cannot hand over.
  o.format = capture::synthetic_pixel_format(c.capture.device.pixel_formats).value();
  return std::make_shared<sim::TrajectoryCamera>(o);
}

// The publisher's options as configured; an empty robot name is the host's,
// as a ROS name.
DdsOptions dds_options(const ServiceConfig& c) {
  DdsOptions o = c.dds.publisher;
  if (o.robot.empty()) {
    char host[256] = {};
    gethostname(host, sizeof(host) - 1);
    o.robot = to_ros_name(host);
  }
  return o;
}

// dds.security.enclave, or the robot name.
std::string enclave_name(const ServiceConfig& c) {
  return c.dds.security.enclave.empty() ? dds_options(c).robot : c.dds.security.enclave;
}

// The configured enclave's files as check_enclave finds them now.
Result<DdsSecurityFiles> checked_enclave(const ServiceConfig& c) {
  auto files =
      keystore::check_enclave(c.dds.security.keystore_dir, enclave_name(c), std::time(nullptr));
  if (!files)
    return make_error("keystore " + c.dds.security.keystore_dir + ": " + files.error().message);
  return files;
}

class Service {
 public:
  Service(const ServiceConfig& config, const DaemonOptions& options)
      : config_(config), options_(options) {}

  int run();

 private:
  // start() runs the steps in order; each returns kExitOk or the exit code.
  int start();
  int check_keystore();
  int start_capture();
  int start_shared_memory();
  int start_dds();
  int start_fleet();
  int start_pipeline();
  void raise_control_priority();
  void loop();
  // What other processes did to the outputs since the last status: the
  // segment written over or truncated, another writer of our DDS topic.
  void report_interference();
  void reload();
  // The running ceiling (map, or nominal grid) on rt/<robot>/ceiling: at
  // start, and again when SIGHUP changes it, so RViz never shows an old map.
  void publish_ceiling();
  void shutdown();
  // The configuration the pipeline runs with: the file's, with a replayed
  // recording's own camera model in place of camera.* unless a calibration
  // file says what the camera is.
  ServiceConfig running_config(ServiceConfig c) const {
    if (replay_intrinsics_ && c.calibration.camera_file.empty())
      c.pipeline.intrinsics = *replay_intrinsics_;
    return c;
  }

  ServiceConfig config_;  // as configured (file + command line); SIGHUP compares against it
  std::optional<CameraIntrinsics> replay_intrinsics_;
  const DaemonOptions& options_;
  SignalChannel signals_;  // first: blocks the signals before any thread exists
  SystemdNotifier notifier_;
  ProblemReport problems_;
  ProgressCounter progress_;
  std::unique_ptr<capture::CaptureThread> capture_;
  std::optional<ShmPoseWriter> shm_;
  // Counts already logged by report_interference().
  shm::SegmentDamage shm_damage_, fleet_damage_;  // reported so far
  size_t reported_other_writers_ = 0;
  std::optional<ShmPoseSink> shm_sink_;
  std::optional<DdsPosePublisher> dds_;
  std::optional<DdsPoseSink> dds_sink_;
  std::unique_ptr<FleetThread> fleet_;  // stopped before dds_ is disposed
  // The enclave's files once check_keystore() found them good; unset: plain DDS.
  std::optional<DdsSecurityFiles> dds_security_;
  std::vector<PublishingSink*> sinks_;
  std::unique_ptr<PipelineWorker> worker_;
  int exit_code_ = kExitOk;
  int64_t start_ns_ = 0;
};

int Service::start() {
  start_ns_ = monotonic_ns();
  for (int (Service::*step)() :
       {&Service::check_keystore, &Service::start_capture, &Service::start_shared_memory,
        &Service::start_dds, &Service::start_fleet, &Service::start_pipeline}) {
    if (const int rc = (this->*step)(); rc != kExitOk) return rc;
  }
  raise_control_priority();
  notifier_.ready("running, waiting for the first frame");
  return kExitOk;
}

// The capture thread opens the source on its own thread.
int Service::start_capture() {
  auto source = capture::make_frame_source(config_.capture.source, source_options(config_),
                                           frame_generator(config_));
  if (!source) {
    spdlog::error("frame source: {}", source.error().message);
    return kExitSourceFailure;
  }
  capture_ =
      std::make_unique<capture::CaptureThread>(std::move(source).value(), config_.capture.thread);
  if (auto r = capture_->start(); !r) {
    spdlog::error("frame source {}: {}", config_.capture.source, r.error().message);
    return kExitSourceFailure;
  }
  // A recording carries its own camera (recording.yaml), as `ceilposectl
  // locate` uses it; a live camera's calibration is the configuration's job.
  CameraIntrinsics recorded;
  if (capture::is_replay_spec(config_.capture.source) && config_.calibration.camera_file.empty() &&
      capture_->camera_intrinsics(&recorded)) {
    replay_intrinsics_ = recorded;
    spdlog::info(
        "camera model from the recording: {}x{} px, fx {} fy {} cx {} cy {} (configuration's "
        "camera.* not used for replay)",
        recorded.width, recorded.height, recorded.fx, recorded.fy, recorded.cx, recorded.cy);
  }
  const capture::RealtimeStatus rt = capture_->realtime();
  spdlog::info(
      "capture: {} ({}{}{})", capture_->description(),
      rt.fifo ? "SCHED_FIFO " + std::to_string(rt.priority) : std::string("normal priority"),
      rt.pinned ? ", pinned" : "", rt.memory_locked ? ", memory locked" : "");
  return kExitOk;
}

int Service::start_shared_memory() {
  shm::ShmErrc code = shm::ShmErrc::kOk;
  auto shm = ShmPoseWriter::create(config_.ipc, &code);
  if (!shm) {
    spdlog::error("shared memory: {}", shm.error().message);
    return code == shm::ShmErrc::kNameTaken || code == shm::ShmErrc::kLiveWriter ? kExitShmNameTaken
                                                                                 : kExitFailure;
  }
  shm_.emplace(std::move(shm).value());
  shm_sink_.emplace(&*shm_, config_.watchdog.status_interval_ms);
  sinks_.push_back(&*shm_sink_);
  return kExitOk;
}

// First of all steps: a keystore that DDS Security would refuse stops the
// daemon before a camera is opened or anything is published.
int Service::check_keystore() {
  const DdsSecurityConfig& sec = config_.dds.security;
  if (!config_.dds.enabled || sec.keystore_dir.empty()) return kExitOk;
  auto files = checked_enclave(config_);
  if (!files) {
    spdlog::error("DDS Security: {}", files.error().message);
    return kExitKeystore;
  }
  dds_security_ = std::move(files).value();
  spdlog::info("DDS Security: enclave {} of keystore {} (authenticated, encrypted)",
               enclave_name(config_), sec.keystore_dir);
  return kExitOk;
}

int Service::start_dds() {
  if (!config_.dds.enabled) return kExitOk;
  DdsOptions options = dds_options(config_);
  options.domain.security = dds_security_;
  auto pub = DdsPosePublisher::create(options);
  if (!pub && dds_security_) {
    // The files were good (check_keystore), so access control refused what
    // the permissions do not grant, e.g. an enclave named for another robot.
    spdlog::error("DDS Security: {} (the permissions of enclave {} must allow publishing rt/{}/*)",
                  pub.error().message, dds_security_->permissions, options.robot);
    return kExitKeystore;
  }
  if (!pub) {
    spdlog::error("DDS: {}", pub.error().message);
    return kExitFailure;
  }
  dds_.emplace(std::move(pub).value());
  if (!dds_->rviz_problem().empty())
    spdlog::warn(
        "DDS: {} not published: {} (an enclave made before ceilpose published them "
        "needs `ceilposectl keys add` again)",
        dds_->publishes_tf() ? "the ceiling is" : "TF (and maybe the ceiling) is",
        dds_->rviz_problem());
  publish_ceiling();
  dds_sink_.emplace(&*dds_, config_.dds.status_period_ms);
  sinks_.push_back(&*dds_sink_);
  spdlog::info("DDS: domain {} topic {}, status every {} ms", dds_->domain_id(), dds_->pose_topic(),
               config_.dds.status_period_ms);
  return kExitOk;
}

// The other robots' poses in <shm>-fleet. A fleet that cannot start stops
// the daemon like any other output that cannot: the configuration asked for it.
int Service::start_fleet() {
  if (!config_.fleet.enabled) return kExitOk;
  if (!dds_) {
    spdlog::warn("fleet: off, because dds.enabled is false (the fleet arrives over DDS)");
    return kExitOk;
  }
  shm::ShmErrc code = shm::ShmErrc::kOk;
  auto fleet = FleetThread::create(config_.fleet, config_.ipc.name, config_.ipc.group,
                                   dds_->participant_handle(), dds_->robot(), &code);
  if (!fleet) {
    spdlog::error("fleet: {}", fleet.error().message);
    return code == shm::ShmErrc::kNameTaken || code == shm::ShmErrc::kLiveWriter ? kExitShmNameTaken
                                                                                 : kExitFailure;
  }
  fleet_ = std::move(fleet).value();
  fleet_->start();
  spdlog::info(
      "fleet: {} holds up to {} robots of DDS domain {} (rt/*/ceilpose_state), stale after "
      "{} ms, removed after {} ms",
      fleet_->segment_name(), config_.fleet.capacity, dds_->domain_id(),
      config_.fleet.stale_after_ms, config_.fleet.remove_after_ms);
  return kExitOk;
}

int Service::start_pipeline() {
  WorkerOptions wopts;
  wopts.rt_priority = config_.capture.pipeline_rt_priority;
  wopts.cpu = config_.capture.thread.cpu;
  worker_ = std::make_unique<PipelineWorker>(running_config(config_), wopts, capture_.get(), sinks_,
                                             &progress_);
  worker_->start();
  if (wopts.rt_priority > 0 && !worker_->realtime())
    spdlog::warn(
        "pipeline thread: SCHED_FIFO {} not permitted (needs LimitRTPRIO or "
        "CAP_SYS_NICE); running at normal priority",
        wopts.rt_priority);
  if (wopts.cpu >= 0 && !worker_->pinned())
    spdlog::warn("pipeline thread: cannot pin to CPU {} (capture.cpu): {}; running on any CPU",
                 wopts.cpu, std::strerror(worker_->pin_error()));
  spdlog::info(
      "ceilposed running: shared memory {}, positioning {}, filter {}{}{}", shm_->name(),
      to_string(config_.pipeline.positioning.mode), config_.pipeline.filter.enabled ? "on" : "off",
      worker_->realtime() ? ", pipeline SCHED_FIFO " + std::to_string(wopts.rt_priority)
                          : std::string(),
      worker_->pinned() ? ", pipeline on CPU " + std::to_string(wopts.cpu) : std::string());
  return kExitOk;
}

// The control thread answers signals and feeds the watchdog. When the frame
// path cannot keep up (a slow board, a synthetic camera rendering back to
// back), its SCHED_FIFO threads take every core and a SCHED_OTHER control
// thread would not run for minutes: SIGTERM went unanswered for 34 min with
// three such daemons on 2 cores. It sleeps almost always, so running it one
// above the frame path costs the frames nothing. Last of the start steps, so
// that no thread (DDS's among them) inherits the priority.
void Service::raise_control_priority() {
  const int frame_path_priority =
      std::max(capture_->realtime().fifo ? capture_->realtime().priority : 0,
               worker_->realtime() ? config_.capture.pipeline_rt_priority : 0);
  if (frame_path_priority == 0) return;
  sched_param param{};
  param.sched_priority = std::min(frame_path_priority + 1, sched_get_priority_max(SCHED_FIFO));
  if (const int r = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); r != 0) {
    spdlog::warn(
        "control thread: cannot run SCHED_FIFO {} above the frame path: {}; SIGTERM and the "
        "watchdog may wait while the frame path is saturated (LimitRTPRIO= must allow {})",
        param.sched_priority, std::strerror(r), param.sched_priority);
    return;
  }
  spdlog::info("control thread: SCHED_FIFO {}, above the frame path's {}", param.sched_priority,
               frame_path_priority);
}

void Service::loop() {
  const int64_t watchdog_period_ns =
      notifier_.watchdog_usec() > 0 ? static_cast<int64_t>(notifier_.watchdog_usec()) * 1000 / 2
                                    : 0;
  if (watchdog_period_ns > 0)
    spdlog::info("systemd watchdog: {} ms, fed every {} ms while frames are processed",
                 notifier_.watchdog_usec() / 1000, watchdog_period_ns / kMsNs);
  WatchdogGate gate(int64_t{config_.watchdog.max_stall_ms} * kMsNs);
  const int64_t status_period_ns = int64_t{config_.watchdog.status_interval_ms} * kMsNs;
  const int64_t problem_period_ns = int64_t{config_.logging.problem_report_interval_ms} * kMsNs;
  const int64_t end_ns =
      options_.duration_s > 0 ? start_ns_ + static_cast<int64_t>(options_.duration_s * 1e9) : 0;

  int64_t now = monotonic_ns();
  int64_t next_watchdog = now;
  int64_t next_status = now + status_period_ns;
  int64_t next_problems = now + problem_period_ns;
  int64_t next_print = now;
  uint64_t printed_frame = 0;
  PosePrinter printer(start_ns_);
  bool stalled_reported = false;

  for (;;) {
    int64_t next = std::min({next_status, next_problems});
    if (watchdog_period_ns > 0) next = std::min(next, next_watchdog);
    if (options_.print_poses) next = std::min(next, next_print);
    if (end_ns > 0) next = std::min(next, end_ns);
    // A state message systemd has not read yet is retried every kQueuedRetryMs.
    const int64_t most_ms = notifier_.has_queued() ? kQueuedRetryMs : 1000;
    const int timeout_ms =
        static_cast<int>(std::clamp<int64_t>((next - now + kMsNs - 1) / kMsNs, 0, most_ms));

    const int sig = signals_.wait(timeout_ms);
    notifier_.flush();
    if (sig == SIGTERM || sig == SIGINT) {
      spdlog::info("{}: stopping", sig == SIGTERM ? "SIGTERM" : "SIGINT");
      return;
    }
    if (sig == SIGHUP) reload();

    now = monotonic_ns();
    if (worker_->finished()) {
      if (capture_->failed()) {
        spdlog::error("frame source {} failed for good; stopping", capture_->description());
        exit_code_ = kExitSourceFailure;
      } else {
        spdlog::info("frame source {} ended; stopping", capture_->description());
      }
      return;
    }
    if (end_ns > 0 && now >= end_ns) {
      spdlog::info("--duration {} s elapsed: stopping", options_.duration_s);
      return;
    }
    if (watchdog_period_ns > 0 && now >= next_watchdog) {
      next_watchdog = now + watchdog_period_ns;
      if (gate.may_feed(progress_, now)) {
        notifier_.watchdog();
        stalled_reported = false;
      } else if (!stalled_reported && progress_.count() > 0) {
        spdlog::error("pipeline made no progress for {} ms: no longer feeding the watchdog",
                      (now - progress_.last_ns()) / kMsNs);
        stalled_reported = true;
      }
    }
    if (now >= next_status) {
      next_status = now + status_period_ns;
      report_interference();
      notifier_.status(status_line(worker_->latest(), worker_->latency()));
    }
    if (now >= next_problems) {
      next_problems = now + problem_period_ns;
      uint64_t failures = 0;
      for (const PublishingSink* sink : sinks_) failures += sink->failures();
      problems_.report(worker_->refusals().snapshot(), failures,
                       static_cast<double>(problem_period_ns) * 1e-9);
      report_dropped_cyclone_lines();
    }
    if (options_.print_poses && now >= next_print) {
      next_print = now + kPrintPeriodNs;
      const PoseSnapshot s = worker_->latest();
      if (s.frame != printed_frame && s.frame != 0) {
        printed_frame = s.frame;
        printer.print(s);
      }
    }
  }
}

void Service::report_interference() {
  if (dds_sink_ && dds_sink_->other_pose_writers() != reported_other_writers_) {
    const size_t before = reported_other_writers_;
    reported_other_writers_ = dds_sink_->other_pose_writers();
    if (reported_other_writers_ > 0) {
      spdlog::warn(
          "DDS: {} writer(s) in another process also publish {} on domain {}: two robots "
          "named '{}', or ceilposed started twice? Subscribers see their poses interleaved; "
          "give each robot its own --robot / dds.robot_name",
          reported_other_writers_, dds_->pose_topic(), dds_->domain_id(), dds_->robot());
    } else if (before > 0) {
      spdlog::info("DDS: {} has no other writer any more", dds_->pose_topic());
    }
  }
  if (shm_)
    report_damage(shm_->name() + " (or its -wake companion)", shm_->name(),
                  {shm_->truncations(), shm_->header_repairs()}, &shm_damage_);
  if (fleet_)
    report_damage(fleet_->segment_name(), fleet_->segment_name(), fleet_->damage(), &fleet_damage_);
}

void Service::reload() {
  notifier_.reloading();
  if (options_.config_path.empty()) {
    spdlog::warn("SIGHUP: started without --config, nothing to reload");
    notifier_.reloaded();
    return;
  }
  // A reload may fail in any way and the daemon goes on as it ran: out of
  // memory too (a huge map under LimitAS=), which used to end it.
  Result<ServiceConfig> next = make_error("not read");
  try {
    next = resolve_config(options_);
  } catch (const std::bad_alloc&) {
    next =
        make_error(options_.config_path +
                   " or a file it names needs more memory than the daemon may use "
                   "(LimitAS=, ulimit -v); is a map or camera file far larger than it should be?");
  }
  if (!next) {
    spdlog::error("SIGHUP: keeping the running configuration: {}", next.error().message);
    notifier_.reloaded();
    return;
  }
  const std::vector<std::string> changed = changed_config_keys(config_, *next);
  std::string applied, needs_restart;
  bool filter_changed = false, ceiling_changed = false;
  for (const auto& key : changed) {
    std::string& list = is_live_key(key) ? applied : needs_restart;
    list += (list.empty() ? "" : ", ") + key;
    filter_changed = filter_changed || key.rfind("filter.", 0) == 0;
    ceiling_changed = ceiling_changed || key.rfind("ceiling.", 0) == 0;
  }
  if (changed.empty()) {
    spdlog::info("SIGHUP: {} unchanged", options_.config_path);
  } else {
    // Only the live keys, so the running config stays what really runs.
    const ServiceConfig live = with_live_keys(config_, *next);
    if (!applied.empty()) {
      worker_->reload(running_config(live), filter_changed);
      set_log_level(live.logging.level);
      spdlog::info("SIGHUP: applied {}", applied);
    }
    if (!needs_restart.empty())
      spdlog::warn("SIGHUP: {} changed but needs a restart (systemctl restart ceilposed)",
                   needs_restart);
    config_ = live;
    if (ceiling_changed) publish_ceiling();
  }
  notifier_.reloaded();
}

void Service::publish_ceiling() {
  if (!dds_) return;
  const PipelineConfig& running = running_config(config_).pipeline;
  const CeilingMap nominal(running.layout);
  if (auto ok = dds_->publish_ceiling(running.layout, running.map ? *running.map : nominal); !ok)
    spdlog::warn("DDS: {}", ok.error().message);
}

void Service::shutdown() {
  notifier_.stopping();
  if (worker_) worker_->stop();
  if (capture_) capture_->stop();
  if (shm_) shm_->mark_stopped();
  if (fleet_) fleet_->stop();
  if (dds_) dds_->dispose();
  if (worker_) {
    const capture::CaptureStats cs = capture_->stats();
    spdlog::info("stopped after {} frames ({} dropped, {} skipped)", worker_->frames(),
                 cs.drops + cs.source_drops, cs.skipped);
    // One journal entry per stage: a multi-line message would lose its prefix.
    std::istringstream report(worker_->latency().report());
    for (std::string line; std::getline(report, line);) spdlog::info("latency {}", line);
  }
}

int Service::run() {
  exit_code_ = start();
  if (exit_code_ == kExitOk) loop();
  shutdown();
  return exit_code_;
}

}  // namespace

int run_service(const ServiceConfig& config, const DaemonOptions& options) {
  Service service(config, options);
  return service.run();
}

std::string keystore_problem(const ServiceConfig& config) {
  if (!config.dds.enabled || config.dds.security.keystore_dir.empty()) return {};
  auto files = checked_enclave(config);
  return files ? std::string() : files.error().message;
}

}  // namespace ceilpose::daemon
