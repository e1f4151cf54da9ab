#include "daemon/signal_channel.h"

#include <gtest/gtest.h>
#include <signal.h>

namespace ceilpose::daemon {
namespace {

TEST(SignalChannel, DeliversSighupAsData) {
  SignalChannel channel;
  ASSERT_EQ(raise(SIGHUP), 0);  // blocked, so it waits in the signalfd instead of killing us
  EXPECT_EQ(channel.wait(1000), SIGHUP);
}

TEST(SignalChannel, TimesOutWithZeroWhenNothingArrives) {
  SignalChannel channel;
  EXPECT_EQ(channel.wait(10), 0);
}

}  // namespace
}  // namespace ceilpose::daemon
