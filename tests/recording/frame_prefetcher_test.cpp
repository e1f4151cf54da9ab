// FramePrefetcher: frames come out in recording order with the pixels
// load_frame gives, a bad frame comes out in its place as its error, and the
// prefetcher can be dropped at any point without waiting for the rest.
// Also built under ThreadSanitizer (label tsan).
#include "recording/frame_prefetcher.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "tests/recording/recording_test_support.h"

namespace ceilpose {
namespace {

using test::TempDir;

class FramePrefetcherTest : public ::testing::TestWithParam<int> {
 protected:
  std::string make_recording(int frames, PixelFormat format = PixelFormat::kRgb24,
                             const std::string& name = "rec") {
    test::RecordingSpec spec;
    spec.frames = frames;
    spec.width = 96;
    spec.height = 64;
    spec.format = format;
    const std::string dir = tmp_.sub(name);
    test::write_recording(dir, spec);
    return dir;
  }
  static bool same_pixels(const Image& a, const Image& b) {
    return a.width() == b.width() && a.height() == b.height() && a.format() == b.format() &&
           a.size_bytes() == b.size_bytes() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
  }
  TempDir tmp_;
};

TEST_P(FramePrefetcherTest, HandsOutEveryFrameInOrderWithTheDecodedPixels) {
  const int threads = GetParam();
  for (const PixelFormat format : {PixelFormat::kRgb24, PixelFormat::kGray8}) {
    SCOPED_TRACE(format == PixelFormat::kRgb24 ? "rgb" : "gray");
    const std::string dir =
        make_recording(23, format, format == PixelFormat::kRgb24 ? "rgb" : "gray");
    auto reader = RecordingReader::open(dir);
    ASSERT_TRUE(reader.ok()) << reader.error().message;
    FramePrefetcher frames(*reader, threads);
    Image expected;
    for (size_t i = 0; i < reader->rows().size(); ++i) {
      auto got = frames.next();
      ASSERT_TRUE(got.ok()) << "frame " << i << ": " << got.error().message;
      ASSERT_TRUE(reader->load_frame(i, &expected).ok());
      EXPECT_TRUE(same_pixels(**got, expected)) << "frame " << i;
    }
    auto past = frames.next();
    ASSERT_FALSE(past.ok());
    test::expect_mentions(past.error().message, {dir, "last frame", "23 frames"});
  }
}

TEST_P(FramePrefetcherTest, ABadFrameComesOutInItsPlaceAfterEveryFrameBeforeIt) {
  const std::string dir = make_recording(12);
  // Cut frame 7's file in half: open() still succeeds (the file exists), so
  // only loading it can tell.
  const std::string victim = dir + "/frames/000007.png";
  const std::string bytes = test::read_text_file(victim);
  test::write_text_file(victim, bytes.substr(0, bytes.size() / 2));
  auto reader = RecordingReader::open(dir);
  ASSERT_TRUE(reader.ok()) << reader.error().message;

  FramePrefetcher frames(*reader, GetParam());
  for (int i = 0; i < 7; ++i) {
    auto got = frames.next();
    EXPECT_TRUE(got.ok()) << "frame " << i << ": " << got.error().message;
  }
  auto bad = frames.next();
  ASSERT_FALSE(bad.ok());
  test::expect_mentions(bad.error().message, {"000007.png", "frames.csv:9"});
  // The frames after it are still there for a caller that wants them.
  auto after = frames.next();
  EXPECT_TRUE(after.ok());
}

TEST_P(FramePrefetcherTest, StartsAtTheFrameAskedFor) {
  const std::string dir = make_recording(9);
  auto reader = RecordingReader::open(dir);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  FramePrefetcher frames(*reader, GetParam(), 5);
  Image expected;
  for (size_t i = 5; i < 9; ++i) {
    auto got = frames.next();
    ASSERT_TRUE(got.ok()) << got.error().message;
    ASSERT_TRUE(reader->load_frame(i, &expected).ok());
    EXPECT_TRUE(same_pixels(**got, expected)) << "frame " << i;
  }
  EXPECT_FALSE(frames.next().ok());
}

TEST_P(FramePrefetcherTest, CanBeDroppedBeforeTheEndOrBeforeAnyFrame) {
  const std::string dir = make_recording(40);
  auto reader = RecordingReader::open(dir);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  { FramePrefetcher untouched(*reader, GetParam()); }
  FramePrefetcher frames(*reader, GetParam());
  ASSERT_TRUE(frames.next().ok());
  ASSERT_TRUE(frames.next().ok());
  // Destruction joins the workers; a hang here is caught by ctest's timeout.
}

TEST(FramePrefetcher, EmptyRangeSaysSoAtOnce) {
  TempDir tmp;
  test::RecordingSpec spec;
  spec.frames = 3;
  test::write_recording(tmp.sub("rec"), spec);
  auto reader = RecordingReader::open(tmp.sub("rec"));
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  FramePrefetcher frames(*reader, 2, 3);
  EXPECT_FALSE(frames.next().ok());
}

TEST(FramePrefetcher, DefaultThreadsIsBetweenOneAndFour) {
  EXPECT_GE(FramePrefetcher::default_threads(), 1);
  EXPECT_LE(FramePrefetcher::default_threads(), 4);
}

INSTANTIATE_TEST_SUITE_P(Threads, FramePrefetcherTest, ::testing::Values(1, 2, 4),
                         [](const auto& info) { return std::to_string(info.param) + "_threads"; });

// Issue 28, defect 14: each thread holds two frames; 16 threads of 32-Mpx
// frames took 4 GB. The budget, not the request, bounds them.
TEST(FramePrefetcherBudget, ThreadsHoldAtMostTheDecodeBudget) {
  const size_t vga = 640 * 480 * 3, mpx32 = size_t{6000} * 5400 * 3;
  EXPECT_EQ(FramePrefetcher::threads_within_budget(16, vga), 16);
  EXPECT_EQ(FramePrefetcher::threads_within_budget(16, mpx32), 4);
  EXPECT_LE((2 * 4 + 2) * mpx32, FramePrefetcher::kDecodeBudgetBytes);
  EXPECT_EQ(FramePrefetcher::threads_within_budget(64, FramePrefetcher::kDecodeBudgetBytes), 1);
  EXPECT_EQ(FramePrefetcher::threads_within_budget(0, 0), 1);
}

}  // namespace
}  // namespace ceilpose
