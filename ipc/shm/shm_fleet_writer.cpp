#include "ipc/shm/shm_fleet_writer.h"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <new>
#include <vector>

#include "core/clock.h"
#include "ipc/shm/pose_record.h"
#include "ipc/shm/shm_segment_file.h"

namespace ceilpose {

using shm::FleetHeader;
using shm::ShmErrc;

namespace {

constexpr mode_t kFleetMode = 0640;
// Room for a few thousand robots; a bigger value is a typo (and 1 GB of RAM).
constexpr uint32_t kMaxCapacity = 65536;

// The pid in an existing fleet segment's header, for the "live writer" message.
int fleet_writer_pid(int fd) { return shm::header_writer_pid<FleetHeader>(fd, shm::kFleetMagic); }

constexpr shm::SegmentOwnerHooks kFleetSegmentHooks{&fleet_writer_pid, nullptr};

std::atomic<uint64_t>* counter_word(FleetHeader* h, FleetCounter c) {
  switch (c) {
    case FleetCounter::kAccepted:
      return &h->accepted;
    case FleetCounter::kRefusedFull:
      return &h->refused_full;
    case FleetCounter::kRefusedFuture:
      return &h->refused_future;
    case FleetCounter::kRefusedPast:
      return &h->refused_past;
    case FleetCounter::kRefusedInvalid:
      return &h->refused_invalid;
    case FleetCounter::kRefusedDuplicate:
      return &h->refused_duplicate;
    case FleetCounter::kRemoved:
      return &h->removed;
  }
  return &h->refused_invalid;
}

}  // namespace

std::string fleet_segment_name(const std::string& shm_name) { return shm_name + shm::kFleetSuffix; }

// The header fields written once at creation, as the writer keeps them.
struct FleetIdentity {
  uint32_t abi_version = 0, header_size = 0, capacity = 0, slot_size = 0, stale_after_ms = 0;
  uint64_t segment_size = 0, generation = 0;
  int32_t writer_pid = 0;
  int64_t start_mono_ns = 0, start_real_ns = 0;

  static FleetIdentity of(const FleetHeader& h) {
    return {h.abi_version,  h.header_size, h.capacity,   h.slot_size,     h.stale_after_ms,
            h.segment_size, h.generation,  h.writer_pid, h.start_mono_ns, h.start_real_ns};
  }
  bool operator==(const FleetIdentity&) const = default;
};

struct ShmFleetWriter::Impl {
  std::string name;
  UniqueFd fd;  // holds the flock that marks a live writer
  shm::Mapping mapping;
  FleetHeader* header = nullptr;
  FleetIdentity identity;
  WriterState state = WriterState::kStarting;
  std::vector<uint8_t> used;  // per slot, sized once
  uint32_t robots = 0;
  uint32_t slots_used = 0;
  bool stopped = false;
  std::atomic<uint64_t> header_repairs{0};

  // Puts the header back if another process overwrote it (or a truncation
  // zeroed it): new readers would say "bad magic" forever. Magic last, as
  // at creation.
  void restore_header() {
    FleetHeader& h = *header;
    const bool intact = h.magic.load(std::memory_order_acquire) == shm::kFleetMagic &&
                        FleetIdentity::of(h) == identity &&
                        h.state.load(std::memory_order_relaxed) == static_cast<uint32_t>(state) &&
                        h.robots.load(std::memory_order_relaxed) == robots &&
                        h.slots_used.load(std::memory_order_relaxed) == slots_used;
    if (intact) return;
    h.magic.store(0, std::memory_order_release);
    h.abi_version = identity.abi_version;
    h.header_size = identity.header_size;
    h.segment_size = identity.segment_size;
    h.capacity = identity.capacity;
    h.slot_size = identity.slot_size;
    h.writer_pid = identity.writer_pid;
    h.stale_after_ms = identity.stale_after_ms;
    h.generation = identity.generation;
    h.start_mono_ns = identity.start_mono_ns;
    h.start_real_ns = identity.start_real_ns;
    h.state.store(static_cast<uint32_t>(state), std::memory_order_relaxed);
    h.robots.store(robots, std::memory_order_relaxed);
    h.slots_used.store(slots_used, std::memory_order_relaxed);
    h.magic.store(shm::kFleetMagic, std::memory_order_release);
    header_repairs.fetch_add(1, std::memory_order_relaxed);
  }

  ~Impl() {
    if (header != nullptr && !stopped) {
      header->state.store(static_cast<uint32_t>(WriterState::kStopped), std::memory_order_release);
    }
  }
};

Result<ShmFleetWriter> ShmFleetWriter::create(const ShmFleetOptions& options, ShmErrc* code) {
  if (code != nullptr) *code = ShmErrc::kOk;
  const std::string& name = options.name;
  if (!shm::valid_shm_name(name) || name.size() > 255) {
    return shm::fail(code, ShmErrc::kInvalidArgument,
                     "invalid shm segment name '" + name + "': must be " + shm::kShmNameRule);
  }
  if (options.capacity == 0 || options.capacity > kMaxCapacity) {
    return shm::fail(code, ShmErrc::kInvalidArgument,
                     "fleet segment " + name + ": capacity must be 1.." +
                         std::to_string(kMaxCapacity) + " robots, got " +
                         std::to_string(options.capacity));
  }
  auto gid = shm::lookup_group(options.group, name, code);
  if (!gid) return gid.error();
  auto fd = shm::claim_name(name, kFleetMode, kFleetSegmentHooks, code);
  if (!fd) return fd.error();
  struct Cleanup {
    const std::string* name;
    bool armed = true;
    ~Cleanup() {
      if (armed) ::shm_unlink(name->c_str());
    }
  } cleanup{&name};
  if (auto r = shm::set_owner_and_mode(fd->get(), name, kFleetMode, *gid, code); !r)
    return r.error();
  const size_t size_bytes = shm::fleet_segment_size(options.capacity);
  auto mapping = shm::size_and_map(fd->get(), name, size_bytes, code);
  if (!mapping) return mapping.error();

  auto impl = std::make_unique<Impl>();
  impl->name = name;
  impl->used.assign(options.capacity, 0);
  auto* h = new (mapping->get()) FleetHeader();
  auto* slots = shm::fleet_slots(h);
  for (uint32_t i = 0; i < options.capacity; ++i) new (&slots[i]) shm::FleetSlot();
  h->abi_version = shm::kFleetAbiVersion;
  h->header_size = sizeof(FleetHeader);
  h->segment_size = size_bytes;
  h->capacity = options.capacity;
  h->slot_size = sizeof(shm::FleetSlot);
  h->writer_pid = ::getpid();
  h->stale_after_ms = options.stale_after_ms;
  h->generation = shm::new_generation();
  h->start_mono_ns = monotonic_ns();
  h->start_real_ns = realtime_ns();
  h->state.store(static_cast<uint32_t>(WriterState::kStarting), std::memory_order_relaxed);
  h->heartbeat_mono_ns.store(h->start_mono_ns, std::memory_order_relaxed);
  h->magic.store(shm::kFleetMagic, std::memory_order_release);
  impl->header = h;
  impl->identity = FleetIdentity::of(*h);
  impl->fd = std::move(fd).value();
  impl->mapping = std::move(mapping).value();
  cleanup.armed = false;
  return ShmFleetWriter(std::move(impl));
}

Result<void> ShmFleetWriter::remove(const std::string& name) {
  if (::shm_unlink(name.c_str()) != 0 && errno != ENOENT) {
    const int e = errno;
    return make_error("cannot remove shm segment " + name + ": " + shm::errno_text(e));
  }
  return {};
}

ShmFleetWriter::ShmFleetWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ShmFleetWriter::ShmFleetWriter(ShmFleetWriter&&) noexcept = default;
ShmFleetWriter& ShmFleetWriter::operator=(ShmFleetWriter&&) noexcept = default;
ShmFleetWriter::~ShmFleetWriter() = default;

uint32_t ShmFleetWriter::capacity() const { return impl_->header->capacity; }

void ShmFleetWriter::store(uint32_t slot, const shm::FleetRecord& record) {
  Impl& w = *impl_;
  if (slot >= w.used.size()) return;
  shm::FleetRecord r = record;
  r.robot[sizeof(r.robot) - 1] = '\0';
  shm::fleet_slots(w.header)[slot].store(r);
  if (w.used[slot] == 0) {
    w.used[slot] = 1;
    ++w.robots;
    w.header->robots.store(w.robots, std::memory_order_release);
  }
  if (slot + 1 > w.slots_used) {
    // After the slot's first store: a reader that sees the count sees the robot.
    w.slots_used = slot + 1;
    w.header->slots_used.store(w.slots_used, std::memory_order_release);
  }
}

void ShmFleetWriter::clear(uint32_t slot) {
  Impl& w = *impl_;
  if (slot >= w.used.size() || w.used[slot] == 0) return;
  const shm::FleetRecord empty{};
  shm::fleet_slots(w.header)[slot].store(empty);
  w.used[slot] = 0;
  --w.robots;
  w.header->robots.store(w.robots, std::memory_order_release);
}

void ShmFleetWriter::count(FleetCounter counter, uint64_t n) {
  counter_word(impl_->header, counter)->fetch_add(n, std::memory_order_relaxed);
}

uint64_t ShmFleetWriter::counted(FleetCounter counter) const {
  return counter_word(impl_->header, counter)->load(std::memory_order_relaxed);
}

uint32_t ShmFleetWriter::robots() const { return impl_->robots; }

void ShmFleetWriter::heartbeat() {
  impl_->restore_header();
  impl_->header->heartbeat_mono_ns.store(monotonic_ns(), std::memory_order_release);
}

void ShmFleetWriter::mark_running() {
  impl_->state = WriterState::kRunning;
  impl_->header->state.store(static_cast<uint32_t>(WriterState::kRunning),
                             std::memory_order_release);
  heartbeat();
}

void ShmFleetWriter::mark_stopped() {
  heartbeat();
  impl_->state = WriterState::kStopped;
  impl_->header->state.store(static_cast<uint32_t>(WriterState::kStopped),
                             std::memory_order_release);
  impl_->stopped = true;
}

const std::string& ShmFleetWriter::name() const { return impl_->name; }
uint64_t ShmFleetWriter::truncations() const { return impl_->mapping.regrown(); }
uint64_t ShmFleetWriter::header_repairs() const {
  return impl_->header_repairs.load(std::memory_order_relaxed);
}

}  // namespace ceilpose
