#include "ipc/shm/shm_pose_writer.h"

#include <fcntl.h>
#include <grp.h>
#include <pthread.h>
#include <pwd.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <mutex>
#include <new>
#include <thread>
#include <vector>

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

constexpr mode_t kSegmentMode = 0640;
// Readers must write the waiter count, so the companion is group-writable.
constexpr mode_t kWakeMode = 0660;

// The writer pid of an existing pose segment, for the "live writer" message.
int existing_writer_pid(int fd) {
  return shm::header_writer_pid<shm::SegmentHeader>(fd, shm::kMagic);
}

// Blocked readers of a segment about to be replaced re-check their writer.
void wake_readers_of(int fd) {
  struct stat st {};
  if (::fstat(fd, &st) != 0 || static_cast<size_t>(st.st_size) != sizeof(Segment)) return;
  int error = 0;
  Mapping m = shm::map_shared(fd, sizeof(Segment), false, shm::OnShrink::kDetach, &error);
  if (m.get() == nullptr) return;
  futex_wake_all(&static_cast<const Segment*>(m.get())->header.wake_seq, FutexScope::kShared);
}

constexpr shm::SegmentOwnerHooks kPoseSegmentHooks{&existing_writer_pid, &wake_readers_of};

}  // namespace

struct ShmPoseWriter::Impl {
  std::string name;
  UniqueFd fd;  // holds the flock that marks a live writer
  Mapping mapping;
  UniqueFd wake_fd;
  Mapping wake_mapping;
  Segment* seg = nullptr;
  WakeSegment* wake = nullptr;
  uint64_t seq = 0;
  uint32_t wake_seq = 0;
  uint64_t wake_syscalls = 0;
  bool running = false;
  bool stopped = false;

  // What the header's identity was made as, to tell when something else
  // (the owner's user or root: readers map it read-only) wrote over it.
  shm::SegmentHeader identity{};
  std::atomic<uint64_t> header_repairs{0};
  // The state this writer last stored, for check_identity (another thread).
  std::atomic<uint32_t> state_of_record{static_cast<uint32_t>(WriterState::kStarting)};
  std::mutex identity_mutex;  // try-locked: one checker at a time, nobody waits

  std::mutex heartbeat_mutex;
  std::condition_variable heartbeat_cv;
  bool heartbeat_stop = false;
  std::thread heartbeat_thread;

  ~Impl() {
    stop_heartbeat_thread();
    if (seg != nullptr && !stopped) mark_stopped();
  }

  void beat() { seg->header.heartbeat_mono_ns.store(monotonic_ns(), std::memory_order_release); }

  void remember_identity() {
    const shm::SegmentHeader& h = seg->header;
    identity.magic.store(h.magic.load(std::memory_order_relaxed), std::memory_order_relaxed);
    identity.abi_version = h.abi_version;
    identity.header_size = h.header_size;
    identity.segment_size = h.segment_size;
    identity.ring_length = h.ring_length;
    identity.pose_size = h.pose_size;
    identity.status_size = h.status_size;
    identity.writer_pid = h.writer_pid;
    identity.generation = h.generation;
    identity.start_mono_ns = h.start_mono_ns;
    identity.start_real_ns = h.start_real_ns;
    identity.stale_after_ms = h.stale_after_ms;
    identity.wake_inode = h.wake_inode;
  }

  // Puts the identity back if it was overwritten (new readers would say
  // "bad magic" forever); the magic last, as at creation.
  void check_identity() {
    std::unique_lock<std::mutex> lock(identity_mutex, std::try_to_lock);
    if (!lock.owns_lock()) return;
    shm::SegmentHeader& h = seg->header;
    const shm::SegmentHeader& i = identity;
    const bool intact =
        h.magic.load(std::memory_order_acquire) == i.magic.load(std::memory_order_relaxed) &&
        h.abi_version == i.abi_version && h.header_size == i.header_size &&
        h.segment_size == i.segment_size && h.ring_length == i.ring_length &&
        h.pose_size == i.pose_size && h.status_size == i.status_size &&
        h.writer_pid == i.writer_pid && h.generation == i.generation &&
        h.start_mono_ns == i.start_mono_ns && h.start_real_ns == i.start_real_ns &&
        h.stale_after_ms == i.stale_after_ms && h.wake_inode == i.wake_inode;
    const uint32_t state = state_of_record.load(std::memory_order_acquire);
    if (h.state.load(std::memory_order_acquire) != state) {
      h.state.store(state, std::memory_order_release);  // zeroed by a truncation, or overwritten
      if (intact) header_repairs.fetch_add(1, std::memory_order_relaxed);
    }
    if (wake->magic.load(std::memory_order_acquire) != shm::kWakeMagic) {
      wake->generation = i.generation;
      wake->magic.store(shm::kWakeMagic, std::memory_order_release);
    }
    if (intact) return;
    h.magic.store(0, std::memory_order_release);
    h.abi_version = i.abi_version;
    h.header_size = i.header_size;
    h.segment_size = i.segment_size;
    h.ring_length = i.ring_length;
    h.pose_size = i.pose_size;
    h.status_size = i.status_size;
    h.writer_pid = i.writer_pid;
    h.generation = i.generation;
    h.start_mono_ns = i.start_mono_ns;
    h.start_real_ns = i.start_real_ns;
    h.stale_after_ms = i.stale_after_ms;
    h.wake_inode = i.wake_inode;
    h.magic.store(i.magic.load(std::memory_order_relaxed), std::memory_order_release);
    header_repairs.fetch_add(1, std::memory_order_relaxed);
  }

  void wake_readers(bool always) {
    wake_seq += 1;
    // seq_cst store and seq_cst load of `waiters`, against the reader's
    // seq_cst increment of `waiters` and load of wake_seq: one side always
    // sees the other, so a reader never sleeps through a publish.
    seg->header.wake_seq.store(wake_seq, std::memory_order_seq_cst);
    if (always || wake->waiters.load(std::memory_order_seq_cst) != 0) {
      futex_wake_all(&seg->header.wake_seq, FutexScope::kShared);
      ++wake_syscalls;
    }
  }

  void mark_stopped() {
    // The last heartbeat then tells readers when the daemon stopped.
    stop_heartbeat_thread();
    {
      std::lock_guard<std::mutex> lock(identity_mutex);
      state_of_record.store(static_cast<uint32_t>(WriterState::kStopped),
                            std::memory_order_release);
      seg->header.state.store(static_cast<uint32_t>(WriterState::kStopped),
                              std::memory_order_release);
    }
    beat();
    stopped = true;
    wake_readers(true);
  }

  void start_heartbeat_thread(int period_ms) {
    heartbeat_thread = std::thread([this, period_ms] {
      ::pthread_setname_np(::pthread_self(), "shm-heartbeat");
      std::unique_lock<std::mutex> lock(heartbeat_mutex);
      while (!heartbeat_cv.wait_for(lock, std::chrono::milliseconds(period_ms),
                                    [this] { return heartbeat_stop; })) {
        check_identity();
        beat();
      }
    });
  }

  void stop_heartbeat_thread() {
    if (!heartbeat_thread.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(heartbeat_mutex);
      heartbeat_stop = true;
    }
    heartbeat_cv.notify_all();
    heartbeat_thread.join();
  }
};

namespace {

Result<void> check_options(const ShmOptions& options, ShmErrc* code) {
  const std::string& name = options.name;
  if (!shm::valid_shm_name(name)) {
    return fail(code, ShmErrc::kInvalidArgument,
                "invalid shm segment name '" + name + "': must be " + shm::kShmNameRule);
  }
  if (options.heartbeat_period_ms < 0) {
    return fail(code, ShmErrc::kInvalidArgument,
                "heartbeat period for shm segment " + name + " must be >= 0 ms, got " +
                    std::to_string(options.heartbeat_period_ms));
  }
  return {};
}

// The companion "-wake" segment, complete (magic stored) before the main one.
Result<void> create_wake_segment(const std::string& name, gid_t gid, uint64_t generation,
                                 UniqueFd* fd_out, Mapping* mapping_out, ShmErrc* code) {
  const std::string wake_name = shm::wake_segment_name(name);
  if (const std::string taken = shm::squatter(wake_name); !taken.empty())
    return fail(code, ShmErrc::kNameTaken, "cannot create shm segment " + wake_name + ": " + taken);
  ::shm_unlink(wake_name.c_str());  // a stale one, if any; ENOENT is normal
  UniqueFd fd(::shm_open(wake_name.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, kWakeMode));
  if (!fd.valid()) {
    const int e = errno;
    return fail(code, shm::errc_from_errno(e),
                "cannot create shm segment " + wake_name + " (mode " + shm::mode_text(kWakeMode) +
                    "): " + shm::errno_text(e));
  }
  if (auto r = shm::set_owner_and_mode(fd.get(), wake_name, kWakeMode, gid, code); !r)
    return r.error();
  auto mapping = shm::size_and_map(fd.get(), wake_name, sizeof(WakeSegment), code);
  if (!mapping) return mapping.error();
  auto* wake = new (mapping->get()) WakeSegment();
  wake->generation = generation;
  wake->magic.store(shm::kWakeMagic, std::memory_order_release);
  *fd_out = std::move(fd);
  *mapping_out = std::move(mapping).value();
  return {};
}

// Fills the pose segment's header; `magic` last, so a reader that sees it
// sees the rest.
Segment* init_pose_segment(void* memory, const ShmOptions& options, uint64_t generation,
                           uint64_t wake_inode) {
  auto* seg = new (memory) Segment();
  auto& h = seg->header;
  h.abi_version = shm::kAbiVersion;
  h.header_size = sizeof(shm::SegmentHeader);
  h.segment_size = sizeof(Segment);
  h.ring_length = shm::kRingLength;
  h.pose_size = sizeof(PoseRecord);
  h.status_size = sizeof(StatusRecord);
  h.writer_pid = ::getpid();
  h.generation = generation;
  h.start_mono_ns = monotonic_ns();
  h.start_real_ns = realtime_ns();
  h.state.store(static_cast<uint32_t>(WriterState::kStarting), std::memory_order_relaxed);
  h.heartbeat_mono_ns.store(h.start_mono_ns, std::memory_order_relaxed);
  h.stale_after_ms = static_cast<uint32_t>(std::max(1, options.stale_after_ms));
  h.wake_inode = wake_inode;
  h.magic.store(shm::kMagic, std::memory_order_release);
  return seg;
}

}  // namespace

Result<ShmPoseWriter> ShmPoseWriter::create(const ShmOptions& options, ShmErrc* code) {
  if (code != nullptr) *code = ShmErrc::kOk;
  const std::string& name = options.name;
  if (auto ok = check_options(options, code); !ok) return ok.error();
  auto gid = shm::lookup_group(options.group, name, code);
  if (!gid) return gid.error();
  auto fd = shm::claim_name(name, kSegmentMode, kPoseSegmentHooks, code);
  if (!fd) return fd.error();

  // Until the segment is complete, any failure removes what was made.
  struct Cleanup {
    const std::string* name;
    bool armed = true;
    ~Cleanup() {
      if (!armed) return;
      ::shm_unlink(name->c_str());
      ::shm_unlink(shm::wake_segment_name(*name).c_str());
    }
  } cleanup{&name};

  if (auto r = shm::set_owner_and_mode(fd->get(), name, kSegmentMode, *gid, code); !r)
    return r.error();
  auto impl = std::make_unique<Impl>();
  impl->name = name;
  const uint64_t generation = shm::new_generation();
  if (auto r =
          create_wake_segment(name, *gid, generation, &impl->wake_fd, &impl->wake_mapping, code);
      !r)
    return r.error();
  auto mapping = shm::size_and_map(fd->get(), name, sizeof(Segment), code);
  if (!mapping) return mapping.error();

  struct stat wake_st {};
  if (::fstat(impl->wake_fd.get(), &wake_st) != 0) {
    const int e = errno;
    return fail(
        code, shm::errc_from_errno(e),
        "cannot stat shm segment " + shm::wake_segment_name(name) + ": " + shm::errno_text(e));
  }
  impl->seg = init_pose_segment(mapping->get(), options, generation, wake_st.st_ino);
  impl->remember_identity();
  impl->wake = static_cast<WakeSegment*>(impl->wake_mapping.get());
  impl->fd = std::move(fd).value();
  impl->mapping = std::move(mapping).value();
  if (options.heartbeat_period_ms > 0) impl->start_heartbeat_thread(options.heartbeat_period_ms);
  cleanup.armed = false;
  return ShmPoseWriter(std::move(impl));
}

Result<void> ShmPoseWriter::remove(const std::string& name) {
  if (!shm::valid_shm_name(name)) {
    return make_error("invalid shm segment name '" + name + "'");
  }
  for (const std::string& n : {name, shm::wake_segment_name(name)}) {
    if (::shm_unlink(n.c_str()) != 0 && errno != ENOENT) {
      const int e = errno;
      return make_error("cannot remove shm segment " + n + ": " + shm::errno_text(e));
    }
  }
  return {};
}

ShmPoseWriter::ShmPoseWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ShmPoseWriter::ShmPoseWriter(ShmPoseWriter&&) noexcept = default;
ShmPoseWriter& ShmPoseWriter::operator=(ShmPoseWriter&&) noexcept = default;
ShmPoseWriter::~ShmPoseWriter() = default;

void ShmPoseWriter::publish(const PoseRecord& pose) {
  Impl& w = *impl_;
  PoseRecord p = pose;
  p.seq = ++w.seq;
  const int64_t now_ns = monotonic_ns();
  if (p.publish_mono_ns == 0) p.publish_mono_ns = now_ns;
  if (p.publish_real_ns == 0) p.publish_real_ns = realtime_ns();
  auto& h = w.seg->header;
  w.seg->latest.store(p);
  w.seg->ring[(p.seq - 1) % shm::kRingLength].store(p);
  h.latest_seq.store(p.seq, std::memory_order_release);
  if (!w.running && !w.stopped) {
    // Once per run; check_identity must not see one of the two stores alone.
    std::lock_guard<std::mutex> lock(w.identity_mutex);
    w.state_of_record.store(static_cast<uint32_t>(WriterState::kRunning),
                            std::memory_order_release);
    h.state.store(static_cast<uint32_t>(WriterState::kRunning), std::memory_order_release);
    w.running = true;
  }
  h.heartbeat_mono_ns.store(now_ns, std::memory_order_release);
  w.wake_readers(false);
}

void ShmPoseWriter::update_status(const StatusRecord& status) {
  StatusRecord s = status;
  if (s.updated_mono_ns == 0) s.updated_mono_ns = monotonic_ns();
  s.source[sizeof(s.source) - 1] = '\0';
  impl_->seg->status.store(s);
}

void ShmPoseWriter::heartbeat() {
  impl_->check_identity();
  impl_->beat();
}

uint64_t ShmPoseWriter::header_repairs() const {
  return impl_->header_repairs.load(std::memory_order_relaxed);
}

uint64_t ShmPoseWriter::truncations() const {
  return impl_->mapping.regrown() + impl_->wake_mapping.regrown();
}

void ShmPoseWriter::mark_stopped() { impl_->mark_stopped(); }

const std::string& ShmPoseWriter::name() const { return impl_->name; }
uint64_t ShmPoseWriter::generation() const { return impl_->seg->header.generation; }
uint64_t ShmPoseWriter::last_seq() const { return impl_->seq; }
uint64_t ShmPoseWriter::wake_syscalls() const { return impl_->wake_syscalls; }

uint32_t ShmPoseWriter::waiting_readers() const {
  return impl_->wake->waiters.load(std::memory_order_seq_cst);
}

}  // namespace ceilpose
