#include "ipc/shm/shm_pose_reader.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/inotify.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <limits>

#include "core/clock.h"
#include "core/futex.h"
#include "ipc/shm/shm_layout.h"
#include "ipc/shm/shm_segment_file.h"

namespace ceilpose {

using shm::fail;
using shm::Mapping;
using shm::Segment;
using shm::ShmErrc;
using shm::WakeSegment;

namespace {

// A reader blocked in wait_next re-checks that its writer still exists this
// often, so a crashed daemon is reported even with an infinite timeout.
constexpr int64_t kLivenessCheckNs = 250'000'000;

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

template <typename T, typename Slot>
bool load_retrying(const Slot& slot, T* out) {
  for (int i = 0; i < ShmPoseReader::kReadRetries; ++i) {
    if (slot.try_load(out)) return true;
    cpu_relax();
  }
  return false;
}

}  // namespace

const char* to_string(ReadResult r) {
  switch (r) {
    case ReadResult::kOk:
      return "ok";
    case ReadResult::kNoPose:
      return "no pose published yet";
    case ReadResult::kBusy:
      return "busy (writer overwrote the pose on every retry)";
  }
  return "?";
}

const char* to_string(WaitResult r) {
  switch (r) {
    case WaitResult::kPose:
      return "pose";
    case WaitResult::kTimeout:
      return "timeout";
    case WaitResult::kStopped:
      return "daemon stopped";
    case WaitResult::kWriterDead:
      return "daemon process gone";
    case WaitResult::kBusy:
      return "busy";
  }
  return "?";
}

const char* to_string(Liveness l) {
  switch (l) {
    case Liveness::kLive:
      return "live";
    case Liveness::kStarting:
      return "starting";
    case Liveness::kStopped:
      return "stopped";
    case Liveness::kStale:
      return "stale";
    case Liveness::kWriterDead:
      return "dead";
    case Liveness::kRestarted:
      return "restarted";
  }
  return "?";
}

struct ShmPoseReader::Impl {
  std::string name;
  UniqueFd fd;
  Mapping mapping;
  UniqueFd wake_fd;
  Mapping wake_mapping;
  const Segment* seg = nullptr;
  WakeSegment* wake = nullptr;
  dev_t dev = 0;
  ino_t ino = 0;
  uint64_t seen_seq = 0;  // the newest latest_seq wait_next saw

  const shm::SegmentHeader& header() const { return seg->header; }
  WriterState state() const {
    return static_cast<WriterState>(header().state.load(std::memory_order_acquire));
  }
  uint64_t latest_seq() const { return header().latest_seq.load(std::memory_order_acquire); }
};

namespace {

// The header must be complete (magic), ours (magic), of our ABI and of the
// sizes this ABI lays out.
Result<void> check_header(const Segment& seg, const struct stat& st, const std::string& name,
                          ShmErrc* code) {
  const auto size_bytes = static_cast<size_t>(st.st_size);
  const uint64_t magic = seg.header.magic.load(std::memory_order_acquire);
  if (magic == 0) return shm::not_ready_or_foreign(name, st, "without a header", code);
  if (magic != shm::kMagic) {
    return fail(code, ShmErrc::kBadMagic,
                "shm segment " + name + " is not a ceilpose pose segment (bad magic)");
  }
  const auto& h = seg.header;
  if (h.abi_version != shm::kAbiVersion) {
    return fail(code, ShmErrc::kAbiMismatch,
                "shm segment " + name + " has ABI version " + std::to_string(h.abi_version) +
                    ", this reader speaks version " + std::to_string(shm::kAbiVersion) +
                    ": update ceilposectl / the client library to match ceilposed");
  }
  if (size_bytes != sizeof(Segment) || h.segment_size != size_bytes ||
      h.header_size != sizeof(shm::SegmentHeader) || h.ring_length != shm::kRingLength ||
      h.pose_size != sizeof(PoseRecord) || h.status_size != sizeof(StatusRecord)) {
    return fail(code, ShmErrc::kBadSize,
                "shm segment " + name + " is " + std::to_string(size_bytes) +
                    " bytes (header says " + std::to_string(h.segment_size) + ", ring " +
                    std::to_string(h.ring_length) + ", pose " + std::to_string(h.pose_size) +
                    " bytes); ABI " + std::to_string(shm::kAbiVersion) + " expects " +
                    std::to_string(sizeof(Segment)) + " bytes, ring " +
                    std::to_string(shm::kRingLength) + ", pose " +
                    std::to_string(sizeof(PoseRecord)) + " bytes");
  }
  return {};
}

// Opens and maps the "-wake" companion read-write; it must be the one the
// pose segment's writer made: the inode its header names (a group reader
// writing garbage into -wake then locks nobody out), or for writers that do
// not record it, the writer's magic and generation.
Result<shm::OpenedSegment> open_wake_segment(const std::string& name, uint64_t generation,
                                             uint64_t wake_inode, ShmErrc* code) {
  const std::string wake_name = shm::wake_segment_name(name);
  shm::OpenedSegment out;
  out.fd = UniqueFd(::shm_open(wake_name.c_str(), O_RDWR | O_CLOEXEC, 0));
  if (!out.fd.valid()) {
    const int e = errno;
    if (e == EACCES) {
      return fail(code, ShmErrc::kPermission,
                  "permission denied opening shm segment " + wake_name +
                      " read-write (needed to wait for poses): " + shm::describe_access(wake_name));
    }
    return fail(code, shm::errc_from_errno(e),
                "cannot open shm segment " + wake_name + " (companion of " + name +
                    "): " + shm::errno_text(e));
  }
  if (::fstat(out.fd.get(), &out.st) != 0 ||
      static_cast<size_t>(out.st.st_size) != sizeof(WakeSegment)) {
    return fail(code, ShmErrc::kNotReady,
                "shm segment " + wake_name + " is " + std::to_string(out.st.st_size) +
                    " bytes, expected " + std::to_string(sizeof(WakeSegment)) +
                    " (its writer is starting or replacing it)");
  }
  int map_error = 0;
  out.mapping =
      shm::map_shared(out.fd.get(), sizeof(WakeSegment), true, shm::OnShrink::kDetach, &map_error);
  if (out.mapping.get() == nullptr) {
    return fail(code, shm::errc_from_errno(map_error),
                "cannot map shm segment " + wake_name + ": " + shm::errno_text(map_error));
  }
  const auto* wake = static_cast<const WakeSegment*>(out.mapping.get());
  const bool belongs = wake_inode != 0
                           ? static_cast<uint64_t>(out.st.st_ino) == wake_inode
                           : wake->magic.load(std::memory_order_acquire) == shm::kWakeMagic &&
                                 wake->generation == generation;
  if (!belongs) {
    return fail(code, ShmErrc::kNotReady,
                "shm segment " + wake_name + " does not belong to " + name +
                    " (its writer is starting or replacing it)");
  }
  return out;
}

}  // namespace

Result<ShmPoseReader> ShmPoseReader::open(const std::string& name, ShmErrc* code) {
  if (code != nullptr) *code = ShmErrc::kOk;
  if (!shm::valid_shm_name(name)) {
    return fail(code, ShmErrc::kInvalidArgument,
                "invalid shm segment name '" + name + "': must be " + shm::kShmNameRule);
  }
  auto pose = shm::open_segment_readonly(
      name, {"pose", offsetof(shm::SegmentHeader, header_size), sizeof(Segment), name}, code);
  if (!pose) return pose.error();
  const auto* seg = static_cast<const Segment*>(pose->mapping.get());
  if (auto ok = check_header(*seg, pose->st, name, code); !ok) return ok.error();
  auto wake = open_wake_segment(name, seg->header.generation, seg->header.wake_inode, code);
  if (!wake) return wake.error();

  auto impl = std::make_unique<Impl>();
  impl->name = name;
  impl->dev = pose->st.st_dev;
  impl->ino = pose->st.st_ino;
  impl->seg = seg;
  impl->wake = static_cast<WakeSegment*>(wake->mapping.get());
  impl->fd = std::move(pose->fd);
  impl->mapping = std::move(pose->mapping);
  impl->wake_fd = std::move(wake->fd);
  impl->wake_mapping = std::move(wake->mapping);
  return ShmPoseReader(std::move(impl));
}

Result<ShmPoseReader> ShmPoseReader::open_waiting(const std::string& name, int timeout_ms,
                                                  ShmErrc* code) {
  const int64_t deadline_ns = timeout_ms < 0 ? std::numeric_limits<int64_t>::max()
                                             : monotonic_ns() + int64_t{timeout_ms} * 1'000'000;
  // Creation shows up as IN_CREATE and sizing as IN_MODIFY; the header's
  // magic is written through the mapping, which inotify cannot see, so the
  // short not-ready window is re-checked on a timer.
  UniqueFd watch(::inotify_init1(IN_CLOEXEC | IN_NONBLOCK));
  if (watch.valid()) {
    ::inotify_add_watch(watch.get(), "/dev/shm", IN_CREATE | IN_MOVED_TO | IN_MODIFY);
  }
  for (;;) {
    ShmErrc local = ShmErrc::kOk;
    auto reader = open(name, &local);
    if (code != nullptr) *code = local;
    if (reader || (local != ShmErrc::kNotFound && local != ShmErrc::kNotReady)) return reader;
    const int64_t remaining_ns = deadline_ns - monotonic_ns();
    if (remaining_ns <= 0) return reader;
    const int64_t slice_ms = local == ShmErrc::kNotReady ? 5 : 250;
    pollfd pfd{watch.get(), POLLIN, 0};
    ::poll(&pfd, 1, static_cast<int>(std::min(remaining_ns / 1'000'000 + 1, slice_ms)));
    char events[4096];
    while (watch.valid() && ::read(watch.get(), events, sizeof events) > 0) {
    }
  }
}

ShmPoseReader::ShmPoseReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ShmPoseReader::ShmPoseReader(ShmPoseReader&&) noexcept = default;
ShmPoseReader& ShmPoseReader::operator=(ShmPoseReader&&) noexcept = default;
ShmPoseReader::~ShmPoseReader() = default;

ReadResult ShmPoseReader::read_latest(PoseRecord* out) const {
  const Impl& r = *impl_;
  if (r.latest_seq() == 0) return ReadResult::kNoPose;
  for (int i = 0; i < kReadRetries; ++i) {
    if (r.seg->latest.try_load(out)) return ReadResult::kOk;
    // The writer is inside the latest slot, perhaps preempted there. The ring
    // slot of latest_seq is complete: the writer stores latest_seq (release)
    // only after writing it, and reuses it only 64 publishes later.
    const uint64_t s = r.latest_seq();
    if (r.seg->ring[(s - 1) % shm::kRingLength].try_load(out) && out->seq == s) {
      return ReadResult::kOk;
    }
    cpu_relax();
  }
  return ReadResult::kBusy;
}

ReadResult ShmPoseReader::read_status(StatusRecord* out) const {
  return load_retrying(impl_->seg->status, out) ? ReadResult::kOk : ReadResult::kBusy;
}

WaitResult ShmPoseReader::wait_next(uint64_t after_seq, int timeout_ms, PoseRecord* out) {
  Impl& r = *impl_;
  const auto& h = r.header();
  const int64_t deadline_ns = timeout_ms < 0 ? std::numeric_limits<int64_t>::max()
                                             : monotonic_ns() + int64_t{timeout_ms} * 1'000'000;
  auto take = [&]() {
    return read_latest(out) == ReadResult::kOk ? WaitResult::kPose : WaitResult::kBusy;
  };
  // A pose newer than after_seq, or a sequence that went back below what
  // this reader saw (something wrote over the segment): waiting for it to
  // pass the old number again would skip every pose in between, silently.
  auto arrived = [&]() {
    const uint64_t s = r.latest_seq();
    const bool went_back = s < r.seen_seq;
    r.seen_seq = s;
    return went_back || s > after_seq;
  };
  for (;;) {
    if (lost()) return WaitResult::kWriterDead;  // liveness() says kRestarted: re-open
    if (arrived()) return take();
    if (r.state() == WriterState::kStopped) return WaitResult::kStopped;
    // Register, then sample the futex word, then re-check: the writer stores
    // the word and then reads `waiters` (both seq_cst), so either it sees us
    // and wakes, or we see its new word and FUTEX_WAIT returns at once.
    r.wake->waiters.fetch_add(1, std::memory_order_seq_cst);
    const uint32_t word = h.wake_seq.load(std::memory_order_seq_cst);
    int rc = 0;
    bool timed_out = false;
    const bool ready = arrived();
    if (!ready && r.state() != WriterState::kStopped) {
      const int64_t remaining_ns = deadline_ns - monotonic_ns();
      if (remaining_ns <= 0) {
        timed_out = true;
      } else {
        rc = futex_wait(&h.wake_seq, word, std::min(remaining_ns, kLivenessCheckNs),
                        FutexScope::kShared);
      }
    }
    r.wake->waiters.fetch_sub(1, std::memory_order_seq_cst);
    if (ready || arrived()) return take();
    if (r.state() == WriterState::kStopped) return WaitResult::kStopped;
    if (timed_out) return WaitResult::kTimeout;
    if (rc == -ETIMEDOUT || rc == 0) {
      // Woken without a pose (a replacing writer wakes us) or a slice ended.
      if (!shm::process_exists(h.writer_pid)) return WaitResult::kWriterDead;
    }
  }
}

Liveness ShmPoseReader::liveness(int64_t stale_after_ms) const {
  if (replaced()) return Liveness::kRestarted;
  const auto& h = impl_->header();
  const WriterState state = impl_->state();
  if (state == WriterState::kStopped) return Liveness::kStopped;
  if (!shm::process_exists(h.writer_pid)) return Liveness::kWriterDead;
  const int64_t age_ns = monotonic_ns() - h.heartbeat_mono_ns.load(std::memory_order_acquire);
  const int64_t stale_ns = this->stale_after_ms(stale_after_ms) * 1'000'000;
  // A heartbeat from the future beyond the staleness limit: this reader's
  // CLOCK_MONOTONIC is not the writer's (another time namespace), and no
  // age can be told; never "live" then.
  if (age_ns > stale_ns || age_ns < -stale_ns) return Liveness::kStale;
  if (state == WriterState::kStarting) return Liveness::kStarting;
  return Liveness::kLive;
}

int ShmPoseReader::read_recent(PoseRecord* out, int max_poses) const {
  const uint64_t newest = impl_->latest_seq();
  int n = 0;
  for (uint64_t s = newest; s > 0 && n < max_poses && newest - s < shm::kRingLength; --s) {
    PoseRecord p;
    if (!load_retrying(impl_->seg->ring[(s - 1) % shm::kRingLength], &p)) break;
    if (p.seq != s) break;  // the writer lapped the ring while we read
    out[n++] = p;
  }
  return n;
}

WriterInfo ShmPoseReader::writer_info() const {
  const auto& h = impl_->header();
  WriterInfo info;
  info.pid = h.writer_pid;
  info.state = impl_->state();
  info.generation = h.generation;
  info.start_mono_ns = h.start_mono_ns;
  info.start_real_ns = h.start_real_ns;
  info.heartbeat_mono_ns = h.heartbeat_mono_ns.load(std::memory_order_acquire);
  info.stale_after_ms = h.stale_after_ms;
  return info;
}

int64_t ShmPoseReader::stale_after_ms(int64_t requested) const {
  return requested > 0 ? requested : int64_t{impl_->header().stale_after_ms};
}

uint64_t ShmPoseReader::latest_seq() const { return impl_->latest_seq(); }

bool ShmPoseReader::replaced() const {
  if (lost()) return true;
  UniqueFd fd(::shm_open(impl_->name.c_str(), O_RDONLY | O_CLOEXEC, 0));
  if (!fd.valid()) return false;
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) return false;
  // Our mapping keeps the old inode alive, so its number cannot be reused.
  return st.st_dev != impl_->dev || st.st_ino != impl_->ino;
}

bool ShmPoseReader::lost() const { return impl_->mapping.lost() || impl_->wake_mapping.lost(); }

Result<void> ShmPoseReader::reattach(ShmErrc* code) {
  auto fresh = open(impl_->name, code);
  if (!fresh) return fresh.error();
  *this = std::move(fresh.value());
  return {};
}

const std::string& ShmPoseReader::name() const { return impl_->name; }

}  // namespace ceilpose
