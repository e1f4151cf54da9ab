// capture/exposure_timing.h: every backend's stamp to the centre row's
// mid-exposure on CLOCK_MONOTONIC.
#include "capture/exposure_timing.h"

#include <gtest/gtest.h>
#include <time.h>

namespace ceilpose::capture {
namespace {

constexpr int64_t kExposureNs = 8'000'000;  // 8 ms
constexpr int64_t kReadoutNs = 30'000'000;  // 30 ms rolling shutter

// One frame on a time line: the first row starts to expose at 100 ms, each
// row exposes for 8 ms, the rows start 30 ms apart from first to last.
constexpr int64_t kFirstRowStartNs = 100'000'000;
constexpr int64_t kCentreMidNs = kFirstRowStartNs + kReadoutNs / 2 + kExposureNs / 2;

TEST(ExposureTiming, EveryStampEventGivesTheSameCentreRowMidExposure) {
  EXPECT_EQ(
      exposure_mid_ns(kFirstRowStartNs, StampEvent::kStartOfExposure, kExposureNs, kReadoutNs),
      kCentreMidNs);
  // The first row is read out when its exposure ends.
  EXPECT_EQ(exposure_mid_ns(kFirstRowStartNs + kExposureNs, StampEvent::kStartOfFrame, kExposureNs,
                            kReadoutNs),
            kCentreMidNs);
  // The last row is read out a readout later.
  EXPECT_EQ(exposure_mid_ns(kFirstRowStartNs + kExposureNs + kReadoutNs, StampEvent::kEndOfFrame,
                            kExposureNs, kReadoutNs),
            kCentreMidNs);
}

TEST(ExposureTiming, AGlobalShutterMovesByHalfTheExposureOnly) {
  EXPECT_EQ(exposure_mid_ns(1'000'000, StampEvent::kEndOfFrame, 2'000'000, 0), 0);
  EXPECT_EQ(exposure_mid_ns(1'000'000, StampEvent::kStartOfExposure, 2'000'000, 0), 2'000'000);
  EXPECT_EQ(exposure_mid_ns(5, StampEvent::kEndOfFrame, 0, 0), 5);
}

TEST(ExposureTiming, BoottimeIsMovedOntoMonotonic) {
  timespec b{}, m{};
  clock_gettime(CLOCK_BOOTTIME, &b);
  clock_gettime(CLOCK_MONOTONIC, &m);
  const int64_t boot_ns = b.tv_sec * 1'000'000'000LL + b.tv_nsec;
  const int64_t mono_ns = m.tv_sec * 1'000'000'000LL + m.tv_nsec;
  const int64_t offset_ns = boottime_minus_monotonic_ns();
  EXPECT_GE(offset_ns, -10'000) << "boot time includes suspend: never behind monotonic";
  // A stamp taken just before the monotonic read lands just before it.
  const int64_t moved_ns = boot_ns - offset_ns;
  EXPECT_LE(moved_ns, mono_ns + 100'000);
  EXPECT_GE(moved_ns, mono_ns - 1'000'000);
}

}  // namespace
}  // namespace ceilpose::capture
