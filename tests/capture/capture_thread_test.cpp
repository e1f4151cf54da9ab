// CaptureThread: real-time settings, latest-frame hand-off, drop policy,
// lossless mode, recovery through the thread.
#include "capture/capture_thread.h"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "capture/v4l2_source.h"
#include "counting_source.h"
#include "fake_v4l2_device.h"

namespace ceilpose::capture {
namespace {

using testing::CountingSource;
using testing::FakeV4l2Device;

CaptureThreadOptions normal_priority() {
  CaptureThreadOptions o;
  o.realtime_priority = 0;
  o.lock_memory = false;
  return o;
}

// Whether this process may use SCHED_FIFO at all, probed on a scratch thread
// so that the answer does not come from the code under test.
bool fifo_permitted(int priority) {
  bool ok = false;
  std::thread probe([&] {
    sched_param sp{};
    sp.sched_priority = priority;
    ok = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
  });
  probe.join();
  return ok;
}

TEST(CaptureThread, RunsSchedFifoAtTheConfiguredPriorityWhenPermitted) {
  if (!fifo_permitted(10)) GTEST_SKIP() << "SCHED_FIFO not permitted here (needs CAP_SYS_NICE)";
  CaptureThreadOptions o = normal_priority();
  o.realtime_priority = 10;
  o.cpu = 0;
  CaptureThread thread(std::make_unique<CountingSource>(CountingSource::Options{}), o);
  ASSERT_TRUE(thread.start());
  int policy = -1;
  sched_param sp{};
  ASSERT_EQ(pthread_getschedparam(thread.native_handle(), &policy, &sp), 0);
  EXPECT_EQ(policy, SCHED_FIFO);
  EXPECT_EQ(sp.sched_priority, 10);
  EXPECT_TRUE(thread.realtime().fifo);
  EXPECT_TRUE(thread.realtime().pinned);
  cpu_set_t set;
  ASSERT_EQ(pthread_getaffinity_np(thread.native_handle(), sizeof set, &set), 0);
  EXPECT_EQ(CPU_COUNT(&set), 1);
  EXPECT_TRUE(CPU_ISSET(0, &set));
  thread.stop();
}

TEST(CaptureThread, WithoutARealtimePriorityStaysSchedOther) {
  CaptureThread thread(std::make_unique<CountingSource>(CountingSource::Options{}),
                       normal_priority());
  ASSERT_TRUE(thread.start());
  int policy = -1;
  sched_param sp{};
  ASSERT_EQ(pthread_getschedparam(thread.native_handle(), &policy, &sp), 0);
  EXPECT_EQ(policy, SCHED_OTHER);
  EXPECT_FALSE(thread.realtime().fifo);
}

TEST(CaptureThread, StartReportsTheSourcesOpenErrorNamingTheDevice) {
  FakeV4l2Device dev("/dev/video0");
  CaptureThread thread(std::make_unique<V4l2Source>("/dev/video9", SourceOptions{}, &dev),
                       normal_priority());
  auto r = thread.start();
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("/dev/video9"), std::string::npos) << r.error().message;
  EXPECT_TRUE(thread.failed());
}

TEST(CaptureThread, AcquireTimesOutWhenNoFrameArrives) {
  CountingSource::Options so;
  so.period_ns = 60'000'000'000;  // the first frame is at t=0, the next in a minute
  CaptureThread thread(std::make_unique<CountingSource>(so), normal_priority());
  ASSERT_TRUE(thread.start());
  Frame f;
  ASSERT_TRUE(thread.acquire_latest(&f, 5000));
  thread.release(f);
  EXPECT_FALSE(thread.acquire_latest(&f, 30));
}

TEST(CaptureThread, ThePipelineGetsTheNewestFrameAndOlderOnesAreSkipped) {
  CountingSource::Options so;
  so.period_ns = 1'000'000;
  auto owned = std::make_unique<CountingSource>(so);
  CountingSource* source = owned.get();
  CaptureThread thread(std::move(owned), normal_priority());
  ASSERT_TRUE(thread.start());
  uint64_t last = 0;
  bool first = true;
  for (int i = 0; i < 8; ++i) {
    // A slow pipeline, by handshake rather than by a sleep: come back only
    // once the camera has delivered three frames more. Delivered counts the
    // frames dropped at a full ring too: a frame that entered the ring
    // before the count was read leaves room for two more only (budget 3),
    // and waiting for three handed would wait out the deadline.
    const auto delivered = [&] {
      const CaptureStats s = thread.stats();
      return s.frames + s.drops;
    };
    const uint64_t before = delivered();
    const int64_t deadline_ns = monotonic_ns() + 30'000'000'000;
    while (delivered() < before + 3 && monotonic_ns() < deadline_ns) std::this_thread::yield();
    ASSERT_GE(delivered(), before + 3) << "the camera stopped delivering frames";
    Frame f;
    ASSERT_TRUE(thread.acquire_latest(&f, 5000));
    uint64_t content;
    std::memcpy(&content, f.image.data, sizeof content);
    EXPECT_EQ(content, f.sequence) << "frame contents changed while the pipeline held it";
    if (!first) {
      EXPECT_GE(f.sequence, last + 3) << "the newest frame, not the next one";
    }
    first = false;
    last = f.sequence;
    thread.release(f);
  }
  thread.stop();
  const CaptureStats s = thread.stats();
  EXPECT_GE(s.skipped + s.drops, 7u * 2) << "each slow turn must shed the older frames";
  EXPECT_EQ(source->protocol_errors(), 0);
  EXPECT_EQ(source->no_free_slot(), 0) << "the in-flight budget must leave the source a buffer";
}

TEST(CaptureThread, DropsNewFramesWhileThePipelineHoldsTheWholeBudget) {
  CountingSource::Options so;
  so.period_ns = 1'000'000;
  so.slots = 4;  // budget 3: one held by the pipeline, two in the ring
  auto owned = std::make_unique<CountingSource>(so);
  CountingSource* source = owned.get();
  CaptureThread thread(std::move(owned), normal_priority());
  ASSERT_TRUE(thread.start());
  Frame held[3];
  for (auto& h : held) ASSERT_TRUE(thread.acquire_latest(&h, 5000));
  // Frames keep arriving at 1 kHz; wait (bounded, for a loaded machine) until
  // the thread has had to drop one.
  for (int i = 0; i < 500 && thread.stats().drops == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_GT(thread.stats().drops, 0u);
  for (auto& h : held) thread.release(h);
  Frame f;
  ASSERT_TRUE(thread.acquire_latest(&f, 5000));  // flows again after the release
  thread.release(f);
  thread.stop();
  EXPECT_EQ(source->protocol_errors(), 0);
  EXPECT_EQ(source->no_free_slot(), 0);
}

TEST(CaptureThread, ALosslessSourceDeliversEveryFrameInOrder) {
  CountingSource::Options so;
  so.period_ns = 0;
  so.frame_limit = 300;
  so.live = false;
  CaptureThread thread(std::make_unique<CountingSource>(so), normal_priority());
  ASSERT_TRUE(thread.start());
  uint64_t expected = 0;
  Frame f;
  while (thread.acquire_latest(&f, 5000)) {
    ASSERT_EQ(f.sequence, expected);
    ++expected;
    thread.release(f);
  }
  EXPECT_EQ(expected, 300u);
  EXPECT_TRUE(thread.finished());
  EXPECT_FALSE(thread.failed());
  EXPECT_EQ(thread.stats().skipped, 0u);
  EXPECT_EQ(thread.stats().drops, 0u);
}

TEST(CaptureThread, RecoversFromAVanishedV4l2DeviceWhileRunning) {
  FakeV4l2Device dev;
  dev.fail_dequeue_at(5, ENODEV, 2);
  SourceOptions so;
  so.reconnect_initial_ms = 5;
  so.reconnect_max_ms = 20;
  CaptureThread thread(std::make_unique<V4l2Source>("/dev/video0", so, &dev), normal_priority());
  ASSERT_TRUE(thread.start());
  // The fake produces a frame per poll, i.e. as fast as the thread asks.
  for (int frames = 0; thread.stats().reconnects == 0 || frames < 20;) {
    Frame f;
    ASSERT_TRUE(thread.acquire_latest(&f, 5000)) << "capture stopped delivering";
    thread.release(f);
    ++frames;
  }
  thread.stop();
  EXPECT_EQ(thread.stats().outages, 1u);
  EXPECT_EQ(thread.stats().reconnects, 1u);
  EXPECT_FALSE(thread.failed());
}

}  // namespace
}  // namespace ceilpose::capture
