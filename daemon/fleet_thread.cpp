#include "daemon/fleet_thread.h"

#include <pthread.h>
#include <spdlog/spdlog.h>

#include "core/clock.h"

namespace ceilpose::daemon {
namespace {

// The longest the thread waits for DDS before it ages robots and beats the
// heartbeat: a tenth of the shortest stale_after_ms allowed (10 ms) would be
// too often for nothing; 20 ms keeps stale marks within 2 % of a 1 s limit.
constexpr int64_t kPollMs = 20;

void log_event(FleetEvent event, const std::string& message) {
  switch (event) {
    case FleetEvent::kJoined:
    case FleetEvent::kRemoved:
      spdlog::info("{}", message);
      break;
    case FleetEvent::kStale:
    case FleetEvent::kRefused:
      spdlog::warn("{}", message);
      break;
    case FleetEvent::kProblem:
      spdlog::error("fleet: {}", message);
      break;
  }
}

}  // namespace

Result<std::unique_ptr<FleetThread>> FleetThread::create(
    const FleetOptions& options, const std::string& shm_name, const std::string& group,
    dds_entity_t participant, const std::string& own_robot, shm::ShmErrc* code) {
  ShmFleetOptions shm_options;
  shm_options.name = fleet_segment_name(shm_name);
  shm_options.group = group;
  shm_options.capacity = options.capacity;
  shm_options.stale_after_ms = static_cast<uint32_t>(options.stale_after_ms);
  auto writer = ShmFleetWriter::create(shm_options, code);
  if (!writer) return writer.error();
  auto subscriber = DdsFleetSubscriber::create(participant, own_robot, options.history_depth);
  if (!subscriber) return subscriber.error();
  return std::unique_ptr<FleetThread>(
      new FleetThread(std::move(writer).value(), std::move(subscriber).value(), options));
}

FleetThread::FleetThread(ShmFleetWriter writer, DdsFleetSubscriber subscriber,
                         const FleetOptions& options)
    : writer_(std::move(writer)),
      subscriber_(std::move(subscriber)),
      keeper_(&writer_, options, &log_event) {}

FleetThread::~FleetThread() { stop(); }

void FleetThread::start() {
  writer_.mark_running();
  thread_ = std::thread([this] { run(); });
}

void FleetThread::stop() {
  stop_.store(true, std::memory_order_release);
  const bool was_running = thread_.joinable();
  if (was_running) thread_.join();
  // No listener may call the keeper once this returns.
  subscriber_.stop_listening();
  if (was_running) {
    const std::lock_guard lock(mutex_);
    writer_.mark_stopped();
  }
}

void FleetThread::LockedKeeper::on_sample(const FleetSample& sample) {
  const std::lock_guard lock(*mutex_);
  keeper_->on_sample(sample);
}

void FleetThread::LockedKeeper::on_problem(const std::string& message) {
  const std::lock_guard lock(*mutex_);
  keeper_->on_problem(message);
}

void FleetThread::run() {
  ::pthread_setname_np(::pthread_self(), "fleet");
  bool failed = false;
  while (!stop_.load(std::memory_order_acquire)) {
    if (auto ok = subscriber_.poll(kPollMs, &locked_keeper_); !ok && !failed) {
      // Reported once: a DDS error here repeats every pass.
      spdlog::error("{}", ok.error().message);
      failed = true;
    }
    const std::lock_guard lock(mutex_);
    keeper_.sweep(monotonic_ns());
    writer_.heartbeat();
  }
}

}  // namespace ceilpose::daemon
