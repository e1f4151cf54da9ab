#pragma once
// SpscRing: a bounded lock-free queue for exactly ONE producer thread and ONE
// consumer thread (after rigtorp/SPSCQueue). try_push() is called only by the
// producer, try_pop()/front()/empty() only by the consumer; size() from either
// is a snapshot. Neither side ever blocks or spins: try_push() on a full ring
// returns false and the producer applies its own drop policy (CaptureThread
// hands the frame straight back to the driver and counts the drop).
//
// Memory order: each side loads its own index relaxed (only it writes it),
// loads the other side's index with acquire (to see the slot contents the
// other side published), and stores its own index with release (to publish
// the slot it filled or freed). Each side caches the other's index and
// re-reads it only when the cached value says full/empty, so the shared cache
// lines bounce only when needed. head/tail live on separate cache lines, and
// the slots are padded away from both, to avoid false sharing.
#include <array>
#include <atomic>
#include <cstddef>
#include <new>
#include <optional>
#include <type_traits>
#include <utility>

namespace ceilpose::capture {

// A fixed 64 keeps the layout identical across compilers (GCC warns that
// std::hardware_destructive_interference_size may vary with -mtune).
inline constexpr size_t kCacheLine_bytes = 64;

// alignas on the class rounds its size up to whole cache lines, so the last
// slot never shares a line with whatever follows the ring in memory.
template <typename T, size_t kCapacity>
class alignas(kCacheLine_bytes) SpscRing {
  static_assert(kCapacity >= 1, "SpscRing needs room for at least one element");
  static_assert(std::is_nothrow_move_constructible_v<T>, "T must move without throwing");
  static_assert(std::is_nothrow_destructible_v<T>, "T must destroy without throwing");
  // One slot stays empty to tell full from empty without a shared counter.
  static constexpr size_t kSlots = kCapacity + 1;

 public:
  SpscRing() = default;
  // Destroys what is left; both threads must be done with the ring.
  ~SpscRing() {
    size_t head = head_.value.load(std::memory_order_acquire);
    const size_t tail = tail_.value.load(std::memory_order_acquire);
    while (head != tail) {
      std::launder(reinterpret_cast<T*>(&slots_[head].storage))->~T();
      head = head + 1 == kSlots ? 0 : head + 1;
    }
  }
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  static constexpr size_t capacity() { return kCapacity; }

  // Producer only. Constructs in place; false when full (nothing constructed).
  template <typename... Args>
  bool try_emplace(Args&&... args) noexcept(std::is_nothrow_constructible_v<T, Args&&...>) {
    const size_t tail = tail_.value.load(std::memory_order_relaxed);
    const size_t next = tail + 1 == kSlots ? 0 : tail + 1;
    if (next == head_cache_) {
      head_cache_ = head_.value.load(std::memory_order_acquire);
      if (next == head_cache_) return false;
    }
    new (&slots_[tail].storage) T(std::forward<Args>(args)...);
    tail_.value.store(next, std::memory_order_release);
    return true;
  }
  bool try_push(const T& v) noexcept(std::is_nothrow_copy_constructible_v<T>) {
    return try_emplace(v);
  }
  bool try_push(T&& v) noexcept { return try_emplace(std::move(v)); }

  // Consumer only. The oldest element, or nullptr when empty.
  T* front() noexcept {
    const size_t head = head_.value.load(std::memory_order_relaxed);
    if (head == tail_cache_) {
      tail_cache_ = tail_.value.load(std::memory_order_acquire);
      if (head == tail_cache_) return nullptr;
    }
    return std::launder(reinterpret_cast<T*>(&slots_[head].storage));
  }
  // Consumer only, after front() returned non-null.
  void pop() noexcept {
    const size_t head = head_.value.load(std::memory_order_relaxed);
    std::launder(reinterpret_cast<T*>(&slots_[head].storage))->~T();
    head_.value.store(head + 1 == kSlots ? 0 : head + 1, std::memory_order_release);
  }
  // Consumer only. Moves the oldest element out.
  std::optional<T> try_pop() noexcept {
    T* p = front();
    if (p == nullptr) return std::nullopt;
    std::optional<T> out{std::move(*p)};
    pop();
    return out;
  }

  // Snapshots; exact only when the other side is idle.
  size_t size() const noexcept {
    const ptrdiff_t diff = static_cast<ptrdiff_t>(tail_.value.load(std::memory_order_acquire)) -
                           static_cast<ptrdiff_t>(head_.value.load(std::memory_order_acquire));
    return static_cast<size_t>(diff < 0 ? diff + static_cast<ptrdiff_t>(kSlots) : diff);
  }
  bool empty() const noexcept { return size() == 0; }

 private:
  struct alignas(kCacheLine_bytes) Index {
    std::atomic<size_t> value{0};
  };
  struct Slot {
    alignas(T) std::byte storage[sizeof(T)];
  };

  // Consumer-owned line: its index and its cache of the producer's index.
  alignas(kCacheLine_bytes) Index head_;
  alignas(kCacheLine_bytes) size_t tail_cache_ = 0;
  // Producer-owned line.
  alignas(kCacheLine_bytes) Index tail_;
  alignas(kCacheLine_bytes) size_t head_cache_ = 0;
  alignas(kCacheLine_bytes) std::array<Slot, kSlots> slots_;
  static_assert(std::atomic<size_t>::is_always_lock_free, "indices must be lock-free atomics");
  static_assert(sizeof(Index) == kCacheLine_bytes, "an index fills exactly one cache line");
};

}  // namespace ceilpose::capture
