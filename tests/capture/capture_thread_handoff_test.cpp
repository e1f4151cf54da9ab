// The capture thread's two-ring hand-off under real concurrency (this binary
// also runs under ThreadSanitizer): a fast camera against a consumer that
// sometimes holds frames; every frame must come back to the source, the
// consumer must see increasing sequences with intact contents, and
// frames = consumed + skipped (+ in the ring at the end).
#include <gtest/gtest.h>

#include <cstring>
#include <thread>

#include "capture/capture_thread.h"
#include "counting_source.h"

namespace ceilpose::capture {
namespace {

using testing::CountingSource;

TEST(CaptureThreadHandoff, EveryFrameIsConsumedSkippedOrDroppedAndAllReturnToTheSource) {
  CountingSource::Options so;
  so.period_ns = 200'000;  // 5 kHz camera
  so.frame_limit = 3000;
  auto owned = std::make_unique<CountingSource>(so);
  CountingSource* source = owned.get();
  CaptureThreadOptions o;
  o.realtime_priority = 0;
  o.lock_memory = false;
  CaptureThread thread(std::move(owned), o);
  ASSERT_TRUE(thread.start());
  uint64_t consumed = 0;
  uint64_t last = 0;
  Frame held{};
  bool holding = false;
  Frame f;
  while (thread.acquire_latest(&f, 5000)) {
    uint64_t content;
    std::memcpy(&content, f.image.data, sizeof content);
    ASSERT_EQ(content, f.sequence);
    if (consumed > 0) {
      ASSERT_GT(f.sequence, last);
    }
    last = f.sequence;
    ++consumed;
    // Hold every 7th frame until the next one, like a pipeline that keeps
    // the previous image for a moment.
    if (holding) {
      thread.release(held);
      holding = false;
    }
    if (consumed % 7 == 0) {
      held = f;
      holding = true;
    } else {
      thread.release(f);
    }
  }
  if (holding) thread.release(held);
  EXPECT_TRUE(thread.finished());
  thread.stop();
  const CaptureStats s = thread.stats();
  EXPECT_EQ(s.frames + s.drops, 3000u);
  EXPECT_EQ(consumed + s.skipped, s.frames);
  EXPECT_EQ(source->protocol_errors(), 0);
  EXPECT_EQ(source->no_free_slot(), 0);
}

}  // namespace
}  // namespace ceilpose::capture
