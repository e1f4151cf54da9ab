#include "ipc/shm/shm_fleet_reader.h"

#include <algorithm>
#include <cstring>

#include "core/clock.h"
#include "ipc/shm/pose_record.h"
#include "ipc/shm/shm_fleet_writer.h"
#include "ipc/shm/shm_segment_file.h"

namespace ceilpose {

using shm::FleetHeader;
using shm::FleetRecord;
using shm::ShmErrc;

namespace {

// A slot the writer rewrites during every attempt is skipped this call.
constexpr int kSlotRetries = 64;

// The record carried to t_mono_ns (0: as received), flagged accordingly;
// stale also when nothing came for stale_after_ns, whatever the keeper said
// (a keeper that died marks nothing).
void carry_to(FleetRecord* r, int64_t t_mono_ns, int64_t now_ns, int64_t stale_after_ns) {
  r->fleet_flags &= ~(CEILPOSE_FLEET_PREDICTED | CEILPOSE_FLEET_NOT_PREDICTED);
  if (now_ns - r->received_mono_ns > stale_after_ns) r->fleet_flags |= CEILPOSE_FLEET_STALE;
  if (t_mono_ns == 0) return;
  if (predict_pose_in_place(&r->pose, t_mono_ns) == PredictResult::kOk) {
    r->fleet_flags |= CEILPOSE_FLEET_PREDICTED;
  } else {
    r->fleet_flags |= CEILPOSE_FLEET_NOT_PREDICTED;
  }
}

bool load_slot(const shm::FleetSlot& slot, FleetRecord* out) {
  for (int i = 0; i < kSlotRetries; ++i) {
    if (slot.try_load_in_place(out)) return true;
  }
  return false;
}

Result<void> check_fleet_header(const FleetHeader& h, const struct stat& st,
                                const std::string& name, ShmErrc* code) {
  const uint64_t magic = h.magic.load(std::memory_order_acquire);
  if (magic == 0) return shm::not_ready_or_foreign(name, st, "without a header", code);
  if (magic != shm::kFleetMagic) {
    return shm::fail(code, ShmErrc::kBadMagic,
                     "shm segment " + name + " is not a ceilpose fleet segment (bad magic)");
  }
  if (h.abi_version != shm::kFleetAbiVersion) {
    return shm::fail(code, ShmErrc::kAbiMismatch,
                     "shm segment " + name + " has fleet ABI version " +
                         std::to_string(h.abi_version) + ", this reader speaks version " +
                         std::to_string(shm::kFleetAbiVersion) +
                         ": update ceilposectl / the client library to match ceilposed");
  }
  const auto size_bytes = static_cast<uint64_t>(st.st_size);
  if (h.header_size != sizeof(FleetHeader) || h.slot_size != sizeof(shm::FleetSlot) ||
      h.segment_size != size_bytes || size_bytes != shm::fleet_segment_size(h.capacity)) {
    return shm::fail(code, ShmErrc::kBadSize,
                     "shm segment " + name + " is " + std::to_string(size_bytes) +
                         " bytes (header says " + std::to_string(h.segment_size) + " for " +
                         std::to_string(h.capacity) + " slots of " + std::to_string(h.slot_size) +
                         " bytes); fleet ABI " + std::to_string(shm::kFleetAbiVersion) +
                         " lays out " + std::to_string(sizeof(FleetHeader)) +
                         " bytes of header and " + std::to_string(sizeof(shm::FleetSlot)) +
                         " a slot");
  }
  return {};
}

}  // namespace

struct ShmFleetReader::Impl {
  std::string name;
  UniqueFd fd;
  shm::Mapping mapping;
  const FleetHeader* header = nullptr;
  uint32_t capacity = 0;

  const shm::FleetSlot* slots() const { return shm::fleet_slots(header); }
  int64_t stale_after_ns() const { return int64_t{header->stale_after_ms} * 1'000'000; }
  uint32_t slots_used() const {
    return std::min(capacity, header->slots_used.load(std::memory_order_acquire));
  }
};

Result<ShmFleetReader> ShmFleetReader::open(const std::string& shm_name, ShmErrc* code) {
  if (code != nullptr) *code = ShmErrc::kOk;
  const std::string name = fleet_segment_name(shm_name);
  if (!shm::valid_shm_name(shm_name)) {
    return shm::fail(code, ShmErrc::kInvalidArgument,
                     "invalid shm segment name '" + shm_name + "': must be " + shm::kShmNameRule);
  }
  // The header first, to learn the capacity; then the whole segment.
  auto opened = shm::open_segment_readonly(
      name, {"fleet", sizeof(FleetHeader), sizeof(FleetHeader), shm_name}, code);
  if (!opened) return opened.error();
  const auto* h = static_cast<const FleetHeader*>(opened->mapping.get());
  if (static_cast<size_t>(opened->st.st_size) < sizeof(FleetHeader)) {
    return shm::not_ready_or_foreign(name, opened->st, "smaller than its header", code);
  }
  if (auto ok = check_fleet_header(*h, opened->st, name, code); !ok) return ok.error();
  const uint32_t capacity = h->capacity;
  int map_error = 0;
  shm::Mapping whole = shm::map_shared(opened->fd.get(), shm::fleet_segment_size(capacity), false,
                                       shm::OnShrink::kDetach, &map_error);
  if (whole.get() == nullptr) {
    return shm::fail(code, shm::errc_from_errno(map_error),
                     "cannot map shm segment " + name + ": " + shm::errno_text(map_error));
  }
  auto impl = std::make_unique<Impl>();
  impl->name = name;
  impl->capacity = capacity;
  impl->header = static_cast<const FleetHeader*>(whole.get());
  impl->fd = std::move(opened->fd);
  impl->mapping = std::move(whole);
  return ShmFleetReader(std::move(impl));
}

ShmFleetReader::ShmFleetReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ShmFleetReader::ShmFleetReader(ShmFleetReader&&) noexcept = default;
ShmFleetReader& ShmFleetReader::operator=(ShmFleetReader&&) noexcept = default;
ShmFleetReader::~ShmFleetReader() = default;

uint32_t ShmFleetReader::read(int64_t t_mono_ns, FleetRecord* out, uint32_t max_robots) const {
  const Impl& r = *impl_;
  uint32_t n = 0;
  const uint32_t used = r.slots_used();
  const int64_t now_ns = monotonic_ns();
  for (uint32_t i = 0; i < used && n < max_robots; ++i) {
    FleetRecord* rec = &out[n];
    if (!load_slot(r.slots()[i], rec) || rec->robot[0] == '\0') continue;
    rec->robot[sizeof(rec->robot) - 1] = '\0';
    carry_to(rec, t_mono_ns, now_ns, r.stale_after_ns());
    ++n;
  }
  return n;
}

bool ShmFleetReader::find(const char* robot, int64_t t_mono_ns, FleetRecord* out) const {
  const Impl& r = *impl_;
  if (robot == nullptr || robot[0] == '\0') return false;
  const uint32_t used = r.slots_used();
  for (uint32_t i = 0; i < used; ++i) {
    if (!load_slot(r.slots()[i], out)) continue;
    out->robot[sizeof(out->robot) - 1] = '\0';
    if (std::strcmp(out->robot, robot) != 0) continue;
    carry_to(out, t_mono_ns, monotonic_ns(), r.stale_after_ns());
    return true;
  }
  return false;
}

FleetInfo ShmFleetReader::info() const {
  const FleetHeader& h = *impl_->header;
  FleetInfo i{};
  i.pid = h.writer_pid;
  i.state = h.state.load(std::memory_order_acquire);
  i.generation = h.generation;
  i.heartbeat_mono_ns = h.heartbeat_mono_ns.load(std::memory_order_acquire);
  i.capacity = h.capacity;
  i.robots = h.robots.load(std::memory_order_acquire);
  i.stale_after_ms = h.stale_after_ms;
  i.accepted = h.accepted.load(std::memory_order_relaxed);
  i.refused_full = h.refused_full.load(std::memory_order_relaxed);
  i.refused_future = h.refused_future.load(std::memory_order_relaxed);
  i.refused_past = h.refused_past.load(std::memory_order_relaxed);
  i.refused_invalid = h.refused_invalid.load(std::memory_order_relaxed);
  i.refused_duplicate = h.refused_duplicate.load(std::memory_order_relaxed);
  i.removed = h.removed.load(std::memory_order_relaxed);
  return i;
}

const std::string& ShmFleetReader::name() const { return impl_->name; }

}  // namespace ceilpose
