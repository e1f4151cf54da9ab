// ReplaySource: pacing by recorded timestamps, speed factor, fast mode, loop,
// and errors that name the recording.
#include "capture/replay_source.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "capture/capture_thread.h"
#include "core/clock.h"
#include "recording/recording_writer.h"

namespace ceilpose::capture {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 10;
constexpr int64_t kInterval_ns = 20'000'000;
// How late a paced frame may be delivered after its schedule: far above a
// loaded CI machine's scheduling delay (tens of ms), far below what a source
// that sleeps in the wrong unit (20 ms read as 20 s) or past its schedule
// accumulates. The schedule itself is checked exactly.
constexpr int64_t kMaxLatenessNs = 1'000'000'000;

// A small recording: kFrames 32x24 frames, 20 ms apart, with ground truth
// x = index, and pixel (0,0) red = index.
class ReplaySourceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("ceilpose_replay_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    RecordingCamera camera;
    camera.intrinsics.width = 32;
    camera.intrinsics.height = 24;
    camera.source = "capture test";
    auto w = RecordingWriter::create(dir_.string(), camera);
    ASSERT_TRUE(w) << w.error().message;
    Image img(32, 24, PixelFormat::kRgb24);
    for (int i = 0; i < kFrames; ++i) {
      std::fill(img.data(), img.data() + img.size_bytes(), uint8_t{0});
      img.data()[0] = static_cast<uint8_t>(i);
      const Pose2D gt{static_cast<double>(i), 0.5, 0.25};
      auto r = w->append(img.view(), 5'000'000'000 + i * kInterval_ns, &gt);
      ASSERT_TRUE(r) << r.error().message;
    }
    ASSERT_TRUE(w->close());
  }
  void TearDown() override { fs::remove_all(dir_); }

  SourceOptions options(bool fast, double speed = 1.0, bool loop = false) {
    SourceOptions o;
    o.replay_speed = fast ? 0.0 : speed;
    o.replay_loop = loop;
    return o;
  }

  fs::path dir_;
};

NextStatus next_blocking(FrameSource& s, Frame* f) {
  NextStatus st;
  int calls = 0;
  while ((st = s.next(f, 50)) == NextStatus::kTimeout && ++calls < 200) {
  }
  return st;
}

TEST_F(ReplaySourceTest, FastModeDeliversEveryFrameInOrderWithGroundTruth) {
  ReplaySource source(dir_.string(), options(true));
  ASSERT_TRUE(source.open());
  ASSERT_TRUE(source.start());
  EXPECT_FALSE(source.live());
  for (int i = 0; i < kFrames; ++i) {
    Frame f;
    ASSERT_EQ(next_blocking(source, &f), NextStatus::kFrame);
    EXPECT_EQ(f.source_index, i);
    EXPECT_EQ(f.source_timestamp_ns, 5'000'000'000 + i * kInterval_ns);
    ASSERT_TRUE(f.has_ground_truth);
    EXPECT_DOUBLE_EQ(f.ground_truth.x_m, i);
    EXPECT_EQ(f.image.data[0], i);
    source.release(f);
  }
  Frame f;
  EXPECT_EQ(source.next(&f, 10), NextStatus::kEndOfStream);
}

TEST_F(ReplaySourceTest, RealTimePacingFollowsTheRecordedTimestamps) {
  ReplaySource source(dir_.string(), options(false));
  ASSERT_TRUE(source.open());
  const int64_t started_ns = monotonic_ns();
  ASSERT_TRUE(source.start());
  int64_t first_capture_ns = 0;
  int64_t last_dequeue_ns = 0;
  for (int i = 0; i < kFrames; ++i) {
    Frame f;
    ASSERT_EQ(next_blocking(source, &f), NextStatus::kFrame);
    EXPECT_EQ(f.source_index, i);
    if (i == 0) first_capture_ns = f.capture_ns;
    // The schedule is exact; delivery is never early (absolute sleeps).
    EXPECT_EQ(f.capture_ns - first_capture_ns, i * kInterval_ns);
    EXPECT_GE(f.dequeue_ns, f.capture_ns);
    EXPECT_LT(f.dequeue_ns - f.capture_ns, kMaxLatenessNs) << "frame " << i;
    last_dequeue_ns = f.dequeue_ns;
    source.release(f);
  }
  const int64_t elapsed_ns = last_dequeue_ns - started_ns;
  EXPECT_GE(elapsed_ns, (kFrames - 1) * kInterval_ns);
  EXPECT_LT(elapsed_ns, (kFrames - 1) * kInterval_ns + 5'000'000'000) << "generous: loaded CI";
}

TEST_F(ReplaySourceTest, ASpeedFactorDividesTheRecordedIntervals) {
  ReplaySource source(dir_.string(), options(false, 4.0));
  ASSERT_TRUE(source.open());
  ASSERT_TRUE(source.start());
  int64_t first_ns = 0;
  for (int i = 0; i < kFrames; ++i) {
    Frame f;
    ASSERT_EQ(next_blocking(source, &f), NextStatus::kFrame);
    if (i == 0) first_ns = f.capture_ns;
    EXPECT_EQ(f.capture_ns - first_ns, i * kInterval_ns / 4);
    EXPECT_GE(f.dequeue_ns, f.capture_ns);
    // Nor late (kMaxLatenessNs).
    EXPECT_LT(f.dequeue_ns - f.capture_ns, kMaxLatenessNs) << "frame " << i;
    source.release(f);
  }
}

TEST_F(ReplaySourceTest, LoopStartsOverOneIntervalAfterTheLastFrame) {
  ReplaySource source(dir_.string(), options(false, 10.0, true));
  ASSERT_TRUE(source.open());
  ASSERT_TRUE(source.start());
  int64_t first_ns = 0;
  for (int i = 0; i < 2 * kFrames + 3; ++i) {
    Frame f;
    ASSERT_EQ(next_blocking(source, &f), NextStatus::kFrame);
    if (i == 0) first_ns = f.capture_ns;
    EXPECT_EQ(f.source_index, i % kFrames);
    EXPECT_EQ(f.sequence, static_cast<uint64_t>(i));
    EXPECT_EQ(f.capture_ns - first_ns, i * kInterval_ns / 10);
    source.release(f);
  }
}

TEST_F(ReplaySourceTest, ThroughTheCaptureThreadFastModeDeliversEveryFrame) {
  CaptureThreadOptions o;
  o.realtime_priority = 0;
  o.lock_memory = false;
  CaptureThread thread(std::make_unique<ReplaySource>(dir_.string(), options(true)), o);
  ASSERT_TRUE(thread.start());
  int64_t expected = 0;
  Frame f;
  while (thread.acquire_latest(&f, 5000)) {
    EXPECT_EQ(f.source_index, expected);
    ++expected;
    thread.release(f);
  }
  EXPECT_EQ(expected, kFrames);
  EXPECT_FALSE(thread.failed());
}

TEST_F(ReplaySourceTest, AMissingRecordingFailsInOpenNamingTheDirectory) {
  ReplaySource source((dir_ / "nope").string(), options(true));
  auto r = source.open();
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("nope"), std::string::npos) << r.error().message;
}

TEST_F(ReplaySourceTest, ACorruptFrameStopsTheReplayWithAnErrorNotASkip) {
  // Truncate frame 3's file.
  const fs::path frame3 = dir_ / "frames" / "000003.png";
  ASSERT_TRUE(fs::exists(frame3));
  fs::resize_file(frame3, 20);
  ReplaySource source(dir_.string(), options(true));
  auto opened = source.open();
  if (!opened) {
    // The reader may already reject it at open; then it must name the file.
    EXPECT_NE(opened.error().message.find("000003"), std::string::npos) << opened.error().message;
    return;
  }
  ASSERT_TRUE(source.start());
  for (int i = 0; i < 3; ++i) {
    Frame f;
    ASSERT_EQ(next_blocking(source, &f), NextStatus::kFrame);
    source.release(f);
  }
  Frame f;
  EXPECT_EQ(source.next(&f, 50), NextStatus::kError);
}

}  // namespace
}  // namespace ceilpose::capture
