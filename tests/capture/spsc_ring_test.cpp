// SpscRing: single-thread semantics, object lifetimes, and two threads pushing
// millions of handles through it (built under ThreadSanitizer by scripts/test).
#include "capture/spsc_ring.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace ceilpose::capture {
namespace {

#if defined(__SANITIZE_THREAD__)
constexpr uint64_t kItems = 200'000;  // TSan is ~10x slower; still a long interleaving
#else
constexpr uint64_t kItems = 4'000'000;
#endif

// Counts live instances so that the ring is seen to construct and destroy
// each element exactly once.
struct Tracked {
  static std::atomic<int64_t> live;
  static std::atomic<int64_t> constructed;
  uint64_t value;
  explicit Tracked(uint64_t v) noexcept : value(v) {
    live.fetch_add(1, std::memory_order_relaxed);
    constructed.fetch_add(1, std::memory_order_relaxed);
  }
  Tracked(const Tracked& o) noexcept : Tracked(o.value) {}
  Tracked(Tracked&& o) noexcept : Tracked(o.value) {}
  Tracked& operator=(const Tracked&) = delete;
  ~Tracked() { live.fetch_sub(1, std::memory_order_relaxed); }
};
std::atomic<int64_t> Tracked::live{0};
std::atomic<int64_t> Tracked::constructed{0};

TEST(SpscRing, PopsInPushOrder) {
  SpscRing<int, 4> ring;
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(ring.try_push(i));
  for (int i = 0; i < 4; ++i) {
    auto v = ring.try_pop();
    ASSERT_TRUE(v.has_value());
    EXPECT_EQ(*v, i);
  }
  EXPECT_FALSE(ring.try_pop().has_value());
}

TEST(SpscRing, APushToAFullRingFailsAndLeavesItUnchanged) {
  SpscRing<int, 3> ring;
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(ring.try_push(i));
  EXPECT_FALSE(ring.try_push(99));
  EXPECT_EQ(ring.size(), 3u);
  EXPECT_EQ(*ring.front(), 0);
}

TEST(SpscRing, WrapsAroundManyTimes) {
  SpscRing<uint64_t, 5> ring;
  uint64_t next_push = 0;
  uint64_t next_pop = 0;
  for (int round = 0; round < 1000; ++round) {
    const int burst = round % 5 + 1;  // 1..5: the indices meet at every slot
    for (int k = 0; k < burst; ++k) ASSERT_TRUE(ring.try_push(next_push++));
    for (int k = 0; k < burst; ++k) ASSERT_EQ(*ring.try_pop(), next_pop++);
    ASSERT_TRUE(ring.empty());
  }
  EXPECT_EQ(next_pop, next_push);
}

TEST(SpscRing, ConstructsAndDestroysEachElementExactlyOnce) {
  Tracked::live = 0;
  Tracked::constructed = 0;
  {
    SpscRing<Tracked, 8> ring;
    for (uint64_t i = 0; i < 8; ++i) ASSERT_TRUE(ring.try_emplace(i));
    EXPECT_EQ(Tracked::live.load(), 8);
    EXPECT_FALSE(ring.try_emplace(uint64_t{100}));
    EXPECT_EQ(Tracked::live.load(), 8) << "a failed push constructs nothing";
    EXPECT_EQ(Tracked::constructed.load(), 8);
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(ring.try_pop().has_value());
    EXPECT_EQ(Tracked::live.load(), 5);
  }
  EXPECT_EQ(Tracked::live.load(), 0) << "the destructor destroys what is left";
}

TEST(SpscRing, IndicesSitOnSeparateCacheLines) {
  using Ring = SpscRing<uint64_t, 16>;
  EXPECT_EQ(alignof(Ring), kCacheLine_bytes);
  EXPECT_EQ(sizeof(Ring) % kCacheLine_bytes, 0u);
}

// Lossless: the producer retries a full ring (yielding, this is a test), so
// every value must arrive once, in order: the sum and the sequence agree.
TEST(SpscRing, TwoThreadsMoveMillionsOfHandlesWithoutLossDuplicationOrReordering) {
  Tracked::live = 0;
  {
    SpscRing<Tracked, 64> ring;
    std::thread producer([&] {
      for (uint64_t i = 1; i <= kItems; ++i) {
        while (!ring.try_emplace(i)) std::this_thread::yield();
      }
    });
    uint64_t expected = 1;
    uint64_t sum = 0;
    while (expected <= kItems) {
      Tracked* t = ring.front();
      if (t == nullptr) {
        std::this_thread::yield();
        continue;
      }
      ASSERT_EQ(t->value, expected);
      sum += t->value;
      ring.pop();
      ++expected;
    }
    producer.join();
    EXPECT_EQ(sum, kItems * (kItems + 1) / 2);
    EXPECT_TRUE(ring.empty());
  }
  EXPECT_EQ(Tracked::live.load(), 0);
}

// The capture thread's policy: a full ring drops the new element (never
// blocks). What arrives must be strictly increasing, and arrivals plus drops
// must account for every value, by count and by sum.
TEST(SpscRing, DropNewestPolicyLosesOnlyWhatItCounts) {
  SpscRing<uint64_t, 8> ring;
  std::atomic<bool> done{false};
  uint64_t dropped = 0;
  uint64_t dropped_sum = 0;
  std::thread producer([&] {
    for (uint64_t i = 1; i <= kItems; ++i) {
      if (!ring.try_push(i)) {
        ++dropped;
        dropped_sum += i;
      }
    }
    done.store(true, std::memory_order_release);
  });
  uint64_t received = 0;
  uint64_t received_sum = 0;
  uint64_t last = 0;
  for (;;) {
    const bool finished = done.load(std::memory_order_acquire);
    while (auto v = ring.try_pop()) {
      ASSERT_GT(*v, last) << "reordered or duplicated";
      last = *v;
      ++received;
      received_sum += *v;
    }
    if (finished) break;
    std::this_thread::yield();
  }
  producer.join();
  while (auto v = ring.try_pop()) {
    ASSERT_GT(*v, last);
    last = *v;
    ++received;
    received_sum += *v;
  }
  EXPECT_EQ(received + dropped, kItems);
  EXPECT_EQ(received_sum + dropped_sum, kItems * (kItems + 1) / 2);
  EXPECT_GT(received, 0u);
}

}  // namespace
}  // namespace ceilpose::capture
