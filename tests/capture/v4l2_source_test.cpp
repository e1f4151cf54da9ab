// V4l2Source against the fake driver at the syscall boundary.
#include "capture/v4l2_source.h"

#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>
#include <opencv2/imgcodecs.hpp>

#include "core/clock.h"
#include "fake_v4l2_device.h"

namespace ceilpose::capture {
namespace {

using testing::FakeV4l2Device;

SourceOptions fast_recovery_options() {
  SourceOptions o;
  o.buffer_count = 4;
  o.stall_timeout_ms = 100;
  o.reconnect_initial_ms = 5;
  o.reconnect_max_ms = 40;
  return o;
}

// Calls next() until a frame arrives; false after `calls` attempts.
bool next_frame(FrameSource& source, Frame* f, int calls = 200, int timeout_ms = 20) {
  for (int i = 0; i < calls; ++i) {
    if (source.next(f, timeout_ms) == NextStatus::kFrame) return true;
  }
  return false;
}

// Takes and releases n frames.
::testing::AssertionResult stream_frames(FrameSource& source, int n) {
  for (int i = 0; i < n; ++i) {
    Frame f;
    if (!next_frame(source, &f))
      return ::testing::AssertionFailure() << "frame " << i << " never came";
    source.release(f);
  }
  return ::testing::AssertionSuccess();
}

void open_and_start(FrameSource& source) {
  auto r = source.open();
  ASSERT_TRUE(r) << r.error().message;
  r = source.start();
  ASSERT_TRUE(r) << r.error().message;
}

TEST(V4l2Source, NegotiatesTheFirstPreferredFormatTheDriverAccepts) {
  FakeV4l2Device dev;
  dev.formats = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_RGB24};
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  ASSERT_TRUE(source.open());
  EXPECT_EQ(source.negotiated_format(), PixelFormat::kYuyv);
  EXPECT_EQ(source.width(), 640);
  EXPECT_EQ(source.height(), 480);
  EXPECT_NE(source.describe().find("640x480 YUYV"), std::string::npos) << source.describe();
}

TEST(V4l2Source, FallsThroughToTheNextFormatWhenTheDriverRefusesOneWithEinval) {
  FakeV4l2Device dev;
  dev.formats = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_RGB24};
  dev.refuse_with_einval = {V4L2_PIX_FMT_YUYV};
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  ASSERT_TRUE(source.open());
  EXPECT_EQ(source.negotiated_format(), PixelFormat::kRgb24);
  EXPECT_EQ(dev.current_format(), static_cast<uint32_t>(V4L2_PIX_FMT_RGB24));
}

TEST(V4l2Source, FallsThroughWhenTheDriverSubstitutesAnotherFormat) {
  FakeV4l2Device dev;
  dev.formats = {V4L2_PIX_FMT_BGR24};  // answers every S_FMT with BGR24
  SourceOptions o = fast_recovery_options();
  o.pixel_formats = {PixelFormat::kYuyv, PixelFormat::kRgb24, PixelFormat::kBgr24};
  V4l2Source source("/dev/video0", o, &dev);
  ASSERT_TRUE(source.open());
  EXPECT_EQ(source.negotiated_format(), PixelFormat::kBgr24);
}

TEST(V4l2Source, OpenFailsNamingTheDeviceWhenNoPreferredFormatIsOffered) {
  FakeV4l2Device dev;
  dev.formats = {V4L2_PIX_FMT_GREY};
  SourceOptions o = fast_recovery_options();
  o.pixel_formats = {PixelFormat::kYuyv, PixelFormat::kMjpeg};
  V4l2Source source("/dev/video0", o, &dev);
  auto r = source.open();
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("/dev/video0"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("YUYV"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("MJPEG"), std::string::npos) << r.error().message;
  EXPECT_EQ(dev.open_fds(), 0);
}

TEST(V4l2Source, OpenFailsNamingTheDeviceWhenItDoesNotExist) {
  FakeV4l2Device dev("/dev/video0");
  V4l2Source source("/dev/video7", fast_recovery_options(), &dev);
  auto r = source.open();
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("/dev/video7"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find(std::strerror(ENOENT)), std::string::npos) << r.error().message;
}

TEST(V4l2Source, SetsTheFrameRateThroughStreamParameters) {
  FakeV4l2Device dev;
  SourceOptions o = fast_recovery_options();
  o.fps = 60.0;
  V4l2Source source("/dev/video0", o, &dev);
  ASSERT_TRUE(source.open());
  EXPECT_DOUBLE_EQ(source.fps(), 60.0);
}

TEST(V4l2Source, LocksExposureGainAndWhiteBalanceThroughControls) {
  FakeV4l2Device dev;
  dev.controls[V4L2_CID_EXPOSURE_AUTO] = {0, 3, V4L2_EXPOSURE_APERTURE_PRIORITY};
  dev.controls[V4L2_CID_EXPOSURE_ABSOLUTE] = {1, 5000, 300};
  dev.controls[V4L2_CID_AUTOGAIN] = {0, 1, 1};
  dev.controls[V4L2_CID_GAIN] = {0, 255, 64};
  dev.controls[V4L2_CID_AUTO_WHITE_BALANCE] = {0, 1, 1};
  dev.controls[V4L2_CID_WHITE_BALANCE_TEMPERATURE] = {2800, 6500, 5000};
  SourceOptions o = fast_recovery_options();
  o.controls.exposure_us = 8000;
  o.controls.gain = 32;
  o.controls.white_balance_k = 4600;
  V4l2Source source("/dev/video0", o, &dev);
  ASSERT_TRUE(source.open());
  EXPECT_EQ(dev.control_value(V4L2_CID_EXPOSURE_AUTO), V4L2_EXPOSURE_MANUAL);
  EXPECT_EQ(dev.control_value(V4L2_CID_EXPOSURE_ABSOLUTE), 80);  // 100 µs units
  EXPECT_EQ(dev.control_value(V4L2_CID_AUTOGAIN), 0);
  EXPECT_EQ(dev.control_value(V4L2_CID_GAIN), 32);
  EXPECT_EQ(dev.control_value(V4L2_CID_AUTO_WHITE_BALANCE), 0);
  EXPECT_EQ(dev.control_value(V4L2_CID_WHITE_BALANCE_TEMPERATURE), 4600);
}

TEST(V4l2Source, ClampsAControlValueToTheDriversRange) {
  FakeV4l2Device dev;
  dev.controls[V4L2_CID_WHITE_BALANCE_TEMPERATURE] = {2800, 4000, 3000};
  SourceOptions o = fast_recovery_options();
  o.controls.white_balance_k = 4600;
  V4l2Source source("/dev/video0", o, &dev);
  ASSERT_TRUE(source.open());
  EXPECT_EQ(dev.control_value(V4L2_CID_WHITE_BALANCE_TEMPERATURE), 4000);
}

TEST(V4l2Source, MissingControlsDoNotPreventStreaming) {
  FakeV4l2Device dev;  // no controls at all
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  open_and_start(source);
  Frame f;
  EXPECT_TRUE(next_frame(source, &f));
}

TEST(V4l2Source, FramesPointIntoTheMappedDriverBufferInDequeueOrder) {
  FakeV4l2Device dev;
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  open_and_start(source);
  for (uint64_t i = 0; i < 10; ++i) {
    Frame f;
    ASSERT_TRUE(next_frame(source, &f));
    EXPECT_EQ(f.sequence, i);
    // The fake writes the frame number into the buffer: zero-copy means the
    // frame's pixels are that very buffer.
    EXPECT_EQ(FakeV4l2Device::stamp_of(f.image.data), i);
    EXPECT_EQ(f.buffer_index, static_cast<int32_t>(i % 4));
    EXPECT_EQ(f.image.format, PixelFormat::kYuyv);
    EXPECT_EQ(f.image.stride_bytes, 640 * 2);
    source.release(f);
  }
  const std::vector<uint32_t> expected{0, 1, 2, 3, 0, 1, 2, 3, 0, 1};
  EXPECT_EQ(dev.dequeue_order(), expected);
}

TEST(V4l2Source, ABufferIsRequeuedOnlyWhenItsFrameIsReleased) {
  FakeV4l2Device dev;
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  open_and_start(source);
  Frame held;
  ASSERT_TRUE(next_frame(source, &held));
  for (int i = 0; i < 6; ++i) {
    Frame f;
    ASSERT_TRUE(next_frame(source, &f));
    EXPECT_NE(f.buffer_index, held.buffer_index);
    source.release(f);
  }
  const auto before = dev.queue_order();
  EXPECT_EQ(std::count(before.begin(), before.end(), static_cast<uint32_t>(held.buffer_index)), 1)
      << "queued once at start, never again while held";
  EXPECT_EQ(FakeV4l2Device::stamp_of(held.image.data), 0u) << "held buffer was overwritten";
  source.release(held);
  const auto after = dev.queue_order();
  EXPECT_EQ(after.back(), static_cast<uint32_t>(held.buffer_index));
}

TEST(V4l2Source, MonotonicDriverTimestampsBecomeCaptureTime) {
  FakeV4l2Device dev;
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  open_and_start(source);
  const int64_t before_ns = monotonic_ns();
  Frame f;
  ASSERT_TRUE(next_frame(source, &f));
  EXPECT_TRUE(source.driver_timestamps());
  EXPECT_GE(f.capture_ns, before_ns - 1000);  // timeval keeps µs
  EXPECT_LE(f.capture_ns, f.dequeue_ns);
}

// Issue 13: a frame's time is its centre row's mid-exposure, whichever
// event the driver stamps.
struct StampCase {
  uint32_t source_flag;
  bool exposure_control;
  int64_t expected_shift_ns;  // capture_ns minus the driver's stamp
};

class V4l2Stamps : public ::testing::TestWithParam<StampCase> {};

TEST_P(V4l2Stamps, CaptureTimeIsTheCentreRowsMidExposure) {
  const StampCase c = GetParam();
  FakeV4l2Device dev;
  dev.timestamp_source = c.source_flag;
  if (c.exposure_control) dev.controls[V4L2_CID_EXPOSURE_ABSOLUTE] = {1, 5000, 100};  // 10 ms
  SourceOptions options = fast_recovery_options();
  options.readout_ms = 20.0;
  options.controls.lock_exposure = false;  // the driver's value counts
  V4l2Source source("/dev/video0", options, &dev);
  open_and_start(source);
  for (int k = 0; k < 3; ++k) {
    Frame f;
    ASSERT_TRUE(next_frame(source, &f));
    ASSERT_EQ(dev.stamps_written().size(), static_cast<size_t>(k + 1));
    EXPECT_EQ(f.capture_ns - dev.stamps_written()[static_cast<size_t>(k)], c.expected_shift_ns);
    source.release(f);
  }
  const bool soe = c.source_flag == V4L2_BUF_FLAG_TSTAMP_SRC_SOE;
  EXPECT_NE(source.describe().find(soe ? "start-of-exposure" : "end-of-frame"), std::string::npos)
      << source.describe();
}

INSTANTIATE_TEST_SUITE_P(Kinds, V4l2Stamps,
                         ::testing::Values(
                             // End of frame: back by half the exposure and half the readout.
                             StampCase{V4L2_BUF_FLAG_TSTAMP_SRC_EOF, true, -5'000'000 - 10'000'000},
                             // Start of exposure: forward by the same.
                             StampCase{V4L2_BUF_FLAG_TSTAMP_SRC_SOE, true, 5'000'000 + 10'000'000},
                             // No exposure control: only the readout is known.
                             StampCase{V4L2_BUF_FLAG_TSTAMP_SRC_EOF, false, -10'000'000}));

TEST(V4l2Source, ALockedExposureIsTheOneTheStampsUse) {
  FakeV4l2Device dev;
  dev.controls[V4L2_CID_EXPOSURE_ABSOLUTE] = {1, 5000, 100};
  SourceOptions options = fast_recovery_options();
  options.controls.exposure_us = 4000;  // locked (the default) at 4 ms
  V4l2Source source("/dev/video0", options, &dev);
  open_and_start(source);
  Frame f;
  ASSERT_TRUE(next_frame(source, &f));
  EXPECT_EQ(f.capture_ns - dev.stamps_written().back(), -2'000'000);
}

TEST(V4l2Source, AutoExposureIsFollowedForTheStamps) {
  FakeV4l2Device dev;
  dev.controls[V4L2_CID_EXPOSURE_ABSOLUTE] = {1, 5000, 100};  // 10 ms
  SourceOptions options = fast_recovery_options();
  options.controls.lock_exposure = false;
  V4l2Source source("/dev/video0", options, &dev);
  open_and_start(source);
  EXPECT_NE(source.describe().find("exposure 10.0 ms"), std::string::npos) << source.describe();
  ASSERT_TRUE(stream_frames(source, 1));
  dev.controls[V4L2_CID_EXPOSURE_ABSOLUTE].value = 300;  // auto exposure: 30 ms
  int64_t shift_ns = 0;
  for (int k = 1; k <= 60; ++k) {
    Frame f;
    ASSERT_TRUE(next_frame(source, &f));
    shift_ns = f.capture_ns - dev.stamps_written().back();
    source.release(f);
  }
  EXPECT_EQ(shift_ns, -15'000'000) << "within a second the new exposure counts";
}

TEST(V4l2Source, NonMonotonicDriverTimestampsFallBackToDequeueTime) {
  FakeV4l2Device dev;
  dev.monotonic_timestamps = false;
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  open_and_start(source);
  Frame f;
  ASSERT_TRUE(next_frame(source, &f));
  EXPECT_FALSE(source.driver_timestamps());
  EXPECT_EQ(f.capture_ns, f.dequeue_ns);
  EXPECT_NE(source.describe().find("dequeue-time"), std::string::npos) << source.describe();
  // Dequeue time is after the end of the frame: it moves back like an end-of-frame stamp.
}

TEST(V4l2Source, DriverSequenceGapsAreCountedAsDrops) {
  FakeV4l2Device dev;
  dev.sequence_gap_after = {2, 5};
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  open_and_start(source);
  ASSERT_TRUE(stream_frames(source, 8));
  EXPECT_EQ(source.stats().drops, 2u);
}

TEST(V4l2Source, SpuriousEagainIsNotAnOutage) {
  FakeV4l2Device dev;
  dev.spurious_eagain_at(2);
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  open_and_start(source);
  for (uint64_t i = 0; i < 6; ++i) {
    Frame f;
    ASSERT_TRUE(next_frame(source, &f));
    EXPECT_EQ(FakeV4l2Device::stamp_of(f.image.data), i);
    source.release(f);
  }
  EXPECT_EQ(source.stats().outages, 0u);
  EXPECT_EQ(dev.opens(), 1);
}

TEST(V4l2Source, EioMidStreamIsRecoveredByReopeningTheDevice) {
  FakeV4l2Device dev;
  dev.fail_dequeue_at(3, EIO);
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  open_and_start(source);
  ASSERT_TRUE(stream_frames(source, 10));
  EXPECT_EQ(source.stats().outages, 1u);
  EXPECT_EQ(source.stats().reconnects, 1u);
  EXPECT_EQ(dev.opens(), 2);
  EXPECT_TRUE(dev.streaming());
}

TEST(V4l2Source, VanishedDeviceIsReopenedWithBackoffAndNextNeverHangs) {
  FakeV4l2Device dev;
  dev.fail_dequeue_at(3, ENODEV, /*reopen_failures=*/4);
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  open_and_start(source);
  int frames = 0;
  int timeouts = 0;
  while (frames < 10) {
    Frame f;
    const int64_t t0_ns = monotonic_ns();
    const NextStatus s = source.next(&f, 20);
    // A generous bound: the point is "returns", not "fast".
    ASSERT_LT(monotonic_ns() - t0_ns, 5'000'000'000) << "next() must honour its timeout";
    ASSERT_NE(s, NextStatus::kError);
    ASSERT_LT(timeouts, 500) << "never recovered";
    if (s == NextStatus::kFrame) {
      ++frames;
      source.release(f);
    } else {
      ++timeouts;
    }
  }
  EXPECT_EQ(source.stats().outages, 1u);
  EXPECT_EQ(source.stats().reconnects, 1u);
  EXPECT_EQ(dev.opens(), 2) << "four refused reopen attempts, then one that worked";
  EXPECT_GT(timeouts, 0);
}

TEST(V4l2Source, StalledDeviceTimesOutAndIsRecovered) {
  FakeV4l2Device dev;
  dev.stall_at(3);
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  open_and_start(source);
  ASSERT_TRUE(stream_frames(source, 8));
  EXPECT_EQ(source.stats().outages, 1u);
  EXPECT_EQ(source.stats().reconnects, 1u);
  EXPECT_EQ(dev.opens(), 2);
}

TEST(V4l2Source, AFrameHeldAcrossAnOutageStaysMappedUntilReleased) {
  FakeV4l2Device dev;
  dev.fail_dequeue_at(2, ENODEV);
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  open_and_start(source);
  Frame held;
  ASSERT_TRUE(next_frame(source, &held));
  Frame f;
  ASSERT_TRUE(next_frame(source, &f));
  source.release(f);
  ASSERT_TRUE(next_frame(source, &f));  // through the outage and the reconnect
  source.release(f);
  ASSERT_EQ(source.stats().reconnects, 1u);
  EXPECT_EQ(FakeV4l2Device::stamp_of(held.image.data), 0u);
  EXPECT_EQ(dev.mapped_buffers(), 4 + 1) << "new buffer set plus the held old buffer";
  source.release(held);
  EXPECT_EQ(dev.mapped_buffers(), 4);
}

TEST(V4l2Source, DestructionUnmapsEveryBufferAndClosesTheDevice) {
  FakeV4l2Device dev;
  {
    V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
    open_and_start(source);
    Frame f;
    ASSERT_TRUE(next_frame(source, &f));  // still held at destruction
    EXPECT_EQ(dev.mapped_buffers(), 4);
  }
  EXPECT_EQ(dev.mapped_buffers(), 0);
  EXPECT_EQ(dev.open_fds(), 0);
}

TEST(V4l2Source, MjpegFramesAreDecodedToRgbBeforeDelivery) {
  cv::Mat bgr(48, 64, CV_8UC3, cv::Scalar(40, 30, 200));  // BGR of the marker red
  std::vector<uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", bgr, jpeg));
  FakeV4l2Device dev;
  dev.formats = {V4L2_PIX_FMT_MJPEG};
  dev.mjpeg_payload = jpeg;
  SourceOptions o = fast_recovery_options();
  o.width = 64;
  o.height = 48;
  o.pixel_formats = {PixelFormat::kMjpeg};
  V4l2Source source("/dev/video0", o, &dev);
  open_and_start(source);
  Frame f;
  ASSERT_TRUE(next_frame(source, &f));
  ASSERT_EQ(f.image.format, PixelFormat::kRgb24);
  ASSERT_EQ(f.image.width, 64);
  const uint8_t* px = f.image.row(24) + 32 * 3;
  EXPECT_NEAR(px[0], 200, 6);
  EXPECT_NEAR(px[1], 30, 6);
  EXPECT_NEAR(px[2], 40, 6);
}

TEST(V4l2Source, UndecodableMjpegFramesAreCountedAndSkipped) {
  FakeV4l2Device dev;
  dev.formats = {V4L2_PIX_FMT_MJPEG};
  dev.mjpeg_payload.assign(500, 0x5a);
  SourceOptions o = fast_recovery_options();
  o.width = 64;
  o.height = 48;
  o.pixel_formats = {PixelFormat::kMjpeg};
  V4l2Source source("/dev/video0", o, &dev);
  open_and_start(source);
  Frame f;
  EXPECT_FALSE(next_frame(source, &f, 3, 10));
  EXPECT_GE(source.stats().corrupt, 3u);
  EXPECT_EQ(source.stats().outages, 0u);
}

TEST(V4l2Source, LifecycleCallsOutOfOrderSayWhichStateTheyNeeded) {
  FakeV4l2Device dev;
  V4l2Source source("/dev/video0", fast_recovery_options(), &dev);
  auto r = source.start();
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("needs state Open"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("Closed"), std::string::npos) << r.error().message;
  Frame f;
  EXPECT_EQ(source.next(&f, 1), NextStatus::kError);
  ASSERT_TRUE(source.open());
  r = source.open();
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("needs state Closed"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace ceilpose::capture
