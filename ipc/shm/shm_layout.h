#pragma once
// The bytes of the pose segment (ABI version CEILPOSE_CLIENT_ABI_VERSION).
// docs/ipc.md draws the same layout for people writing other readers.
//
//   offset 0     SegmentHeader    identity (written once, then `magic` published
//                                 with release), writer state, heartbeat, futex word
//   offset 128   latest pose      SeqlockSlot<PoseRecord>
//   then         status           SeqlockSlot<StatusRecord>
//   then         ring[64]         SeqlockSlot<PoseRecord>, pose seq s in ring[(s-1) % 64]
//
// The companion segment "<name>-wake" (mode 0660) holds the only word readers
// write: the count of blocked waiters. It is separate so that the pose
// segment itself stays 0640, read-only for the group.
//
// Seqlock (single writer, any number of readers, correct on ARM and x86; see
// Boehm, "Can seqlocks get along with programming language memory models?",
// 2012). Every payload word is a relaxed std::atomic, so there is no data race
// in the C++ sense and ThreadSanitizer can check it:
//   writer: seq = s+1 (release); fence(release); words (relaxed); seq = s+2 (release)
//   reader: s0 = seq (acquire); words (relaxed); fence(acquire); s1 = seq (relaxed);
//           the copy is whole iff s0 is even and s0 == s1.
// If the reader saw any word of a newer write, the release fence before that
// word makes the odd store visible to the load after its acquire fence, so s1
// differs.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "ipc/shm/pose_record.h"

namespace ceilpose::shm {

inline constexpr uint64_t kMagic = 0x45534f504c494543ULL;  // "CEILPOSE" in memory order
inline constexpr uint64_t kWakeMagic = 0x454b41575045434cULL;
inline constexpr uint32_t kAbiVersion = CEILPOSE_CLIENT_ABI_VERSION;
inline constexpr uint32_t kRingLength = CEILPOSE_POSE_RING_LENGTH;
inline constexpr const char* kWakeSuffix = "-wake";

static_assert(std::atomic<uint64_t>::is_always_lock_free, "shared atomics must be lock-free");
static_assert(std::atomic<uint32_t>::is_always_lock_free, "shared atomics must be lock-free");
static_assert(std::atomic<int64_t>::is_always_lock_free, "shared atomics must be lock-free");

#if defined(__SANITIZE_THREAD__)
// GCC warns that TSan does not model fences; every shared word is atomic, so
// the fences only matter for ordering, which TSan checks conservatively.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wtsan"
#endif

template <typename T>
struct alignas(64) SeqlockSlot {
  static_assert(sizeof(T) % sizeof(uint64_t) == 0, "payload must be whole 64-bit words");
  static constexpr size_t kWords = sizeof(T) / sizeof(uint64_t);

  std::atomic<uint32_t> seq;
  uint32_t reserved;
  std::atomic<uint64_t> words[kWords];

  // Single writer only. Never waits.
  void store(const T& value) {
    uint64_t tmp[kWords];
    std::memcpy(tmp, &value, sizeof(T));
    const uint32_t s = seq.load(std::memory_order_relaxed);
    // Release (not relaxed, which the seqlock alone would allow): a reader that
    // sees this odd value also sees everything published before it, e.g.
    // latest_seq, so falling back to the ring never goes back in time.
    seq.store(s + 1, std::memory_order_release);
    std::atomic_thread_fence(std::memory_order_release);
    for (size_t i = 0; i < kWords; ++i) words[i].store(tmp[i], std::memory_order_relaxed);
    seq.store(s + 2, std::memory_order_release);
  }

  // One attempt straight into *out, which holds a torn copy when it returns
  // false: for readers that retry into the same place anyway (the fleet's
  // snapshot), one copy of the payload instead of two.
  bool try_load_in_place(T* out) const {
    const uint32_t s0 = seq.load(std::memory_order_acquire);
    if ((s0 & 1u) != 0) return false;
    auto* bytes = reinterpret_cast<unsigned char*>(out);
    for (size_t i = 0; i < kWords; ++i) {
      const uint64_t w = words[i].load(std::memory_order_relaxed);
      std::memcpy(bytes + i * sizeof(uint64_t), &w, sizeof w);
    }
    std::atomic_thread_fence(std::memory_order_acquire);
    return seq.load(std::memory_order_relaxed) == s0;
  }

  // One attempt; false when a write overlapped (the caller retries).
  bool try_load(T* out) const {
    const uint32_t s0 = seq.load(std::memory_order_acquire);
    if ((s0 & 1u) != 0) return false;
    uint64_t tmp[kWords];
    for (size_t i = 0; i < kWords; ++i) tmp[i] = words[i].load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (seq.load(std::memory_order_relaxed) != s0) return false;
    std::memcpy(out, tmp, sizeof(T));
    return true;
  }
};

#if defined(__SANITIZE_THREAD__)
#pragma GCC diagnostic pop
#endif

struct alignas(64) SegmentHeader {
  // Identity: written once by the creator before `magic` is stored (release).
  std::atomic<uint64_t> magic;
  uint32_t abi_version;
  uint32_t header_size;
  uint64_t segment_size;
  uint32_t ring_length;
  uint32_t pose_size;
  uint32_t status_size;
  int32_t writer_pid;
  uint64_t generation;  // random per writer start
  int64_t start_mono_ns;
  int64_t start_real_ns;

  // Writer-owned, read by everybody; own cache line.
  alignas(64) std::atomic<uint32_t> state;  // WriterState
  // Futex word: bumped after every publish and on stop; readers FUTEX_WAIT on it.
  std::atomic<uint32_t> wake_seq;
  std::atomic<int64_t> heartbeat_mono_ns;
  std::atomic<uint64_t> latest_seq;  // seq of the pose in `latest`, 0 before the first
  // The writer's ipc.stale_after_ms: what readers call stale unless told
  // otherwise. Written once, before `magic`.
  uint32_t stale_after_ms;
  // The -wake segment's inode, written once before `magic`: readers know
  // their writer's -wake by it, not by its magic and generation, which any
  // reader may overwrite (it is read-write for them). 0 from writers before
  // it existed (then the magic is checked). In what was padding: ABI 3.
  uint64_t wake_inode;
};

struct Segment {
  SegmentHeader header;
  SeqlockSlot<PoseRecord> latest;
  SeqlockSlot<StatusRecord> status;
  SeqlockSlot<PoseRecord> ring[kRingLength];
};

// The companion segment: readers register here before sleeping on the futex,
// so the writer issues FUTEX_WAKE only when someone waits.
struct alignas(64) WakeSegment {
  std::atomic<uint64_t> magic;
  uint64_t generation;  // equals SegmentHeader::generation of its pose segment
  alignas(64) std::atomic<uint32_t> waiters;
};

static_assert(sizeof(SegmentHeader) == 128, "layout of docs/ipc.md");
static_assert(offsetof(Segment, latest) == 128, "layout of docs/ipc.md");
static_assert(offsetof(SegmentHeader, abi_version) == 8, "layout of docs/ipc.md");
static_assert(offsetof(SegmentHeader, writer_pid) == 36, "layout of docs/ipc.md");
static_assert(offsetof(SegmentHeader, generation) == 40, "layout of docs/ipc.md");
static_assert(offsetof(SegmentHeader, start_real_ns) == 56, "layout of docs/ipc.md");
static_assert(offsetof(SegmentHeader, state) == 64, "layout of docs/ipc.md");
static_assert(offsetof(SegmentHeader, wake_seq) == 68, "layout of docs/ipc.md");
static_assert(offsetof(SegmentHeader, heartbeat_mono_ns) == 72, "layout of docs/ipc.md");
static_assert(offsetof(SegmentHeader, latest_seq) == 80, "layout of docs/ipc.md");
static_assert(offsetof(SegmentHeader, wake_inode) == 96, "layout of docs/ipc.md");
static_assert(offsetof(SegmentHeader, stale_after_ms) == 88, "layout of docs/ipc.md");
static_assert(offsetof(Segment, ring) == 1344, "layout of docs/ipc.md");
static_assert(sizeof(SeqlockSlot<PoseRecord>) == 896, "layout of docs/ipc.md");
static_assert(sizeof(SeqlockSlot<StatusRecord>) == 320, "layout of docs/ipc.md");
static_assert(sizeof(Segment) == 128 + 896 + 320 + 896 * kRingLength, "layout of docs/ipc.md");

}  // namespace ceilpose::shm
