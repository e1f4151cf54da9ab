#include "daemon/watchdog_gate.h"

#include <gtest/gtest.h>

namespace ceilpose::daemon {
namespace {

constexpr int64_t kMs = 1'000'000;

TEST(WatchdogGate, RefusesBeforeTheFirstFrame) {
  ProgressCounter progress;
  WatchdogGate gate(500 * kMs);
  EXPECT_FALSE(gate.may_feed(progress, 1000 * kMs));
}

TEST(WatchdogGate, FeedsWhileFramesArrive) {
  ProgressCounter progress;
  WatchdogGate gate(500 * kMs);
  for (int i = 1; i <= 5; ++i) {
    progress.advance(i * 1000 * kMs);
    EXPECT_TRUE(gate.may_feed(progress, i * 1000 * kMs + 1));
  }
}

TEST(WatchdogGate, FeedsWithinTheStallAllowanceWithoutNewFrames) {
  ProgressCounter progress;
  WatchdogGate gate(500 * kMs);
  progress.advance(1000 * kMs);
  EXPECT_TRUE(gate.may_feed(progress, 1000 * kMs));
  EXPECT_TRUE(gate.may_feed(progress, 1400 * kMs));
}

TEST(WatchdogGate, StopsFeedingOnceThePipelineStalls) {
  ProgressCounter progress;
  WatchdogGate gate(500 * kMs);
  progress.advance(1000 * kMs);
  EXPECT_TRUE(gate.may_feed(progress, 1000 * kMs));
  EXPECT_FALSE(gate.may_feed(progress, 1501 * kMs));
  EXPECT_FALSE(gate.may_feed(progress, 5000 * kMs));
}

TEST(WatchdogGate, ResumesWhenFramesComeBack) {
  ProgressCounter progress;
  WatchdogGate gate(500 * kMs);
  progress.advance(1000 * kMs);
  EXPECT_TRUE(gate.may_feed(progress, 1000 * kMs));
  EXPECT_FALSE(gate.may_feed(progress, 9000 * kMs));
  progress.advance(9100 * kMs);
  EXPECT_TRUE(gate.may_feed(progress, 9100 * kMs));
}

}  // namespace
}  // namespace ceilpose::daemon
