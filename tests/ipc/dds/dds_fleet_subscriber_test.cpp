// The daemon's fleet subscriber on loopback: once a robot is discovered its
// samples reach the sink as they arrive, through the reader's listener, with
// no further poll() (the fleet thread no longer wakes per sample; with the
// waitset it used to, none would arrive here), and none after
// stop_listening() returns.
#include "ipc/dds/dds_fleet_subscriber.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <thread>

#include "core/clock.h"
#include "ipc/dds/dds_messages.h"
#include "ipc/dds/dds_pose_publisher.h"
#include "ipc/dds/dds_topic_discovery.h"
#include "tests/ipc/dds/dds_test_env.h"
#include "tests/ipc/fleet/fleet_test_support.h"

namespace ceilpose {
namespace {

class CountingSink final : public FleetSampleSink {
 public:
  void on_sample(const FleetSample& sample) override {
    const std::lock_guard lock(mutex_);
    if (sample.robot != nullptr) robot_ = *sample.robot;
    samples_.fetch_add(1, std::memory_order_release);
  }
  void on_problem(const std::string& message) override {
    const std::lock_guard lock(mutex_);
    problem_ = message;
  }
  int samples() const { return samples_.load(std::memory_order_acquire); }
  std::string robot() {
    const std::lock_guard lock(mutex_);
    return robot_;
  }
  std::string problem() {
    const std::lock_guard lock(mutex_);
    return problem_;
  }

 private:
  std::mutex mutex_;
  std::atomic<int> samples_{0};
  std::string robot_, problem_;
};

bool wait_for(const std::function<bool()>& done, std::chrono::milliseconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

// The fleet reads best effort, keep-last `depth` (docs/decisions.md, issue
// 26): a retransmitted pose would arrive behind the next one, and the
// acknowledgements cost the observer of 50 robots its CPU budget.
TEST(DdsFleetReader, IsBestEffortAndKeepsTheLatestDepthSamples) {
  test::use_loopback_dds();
  const dds_entity_t participant =
      dds_create_participant(test::unique_domain_id(), nullptr, nullptr);
  ASSERT_GT(participant, 0);
  const dds_entity_t waitset = dds_create_waitset(participant);
  const auto reader = create_fleet_reader(participant, waitset, &ceilpose_msg_dds__State__desc,
                                          "rt/somebody/ceilpose_state", 8);
  ASSERT_TRUE(reader) << reader.error().message;
  dds_qos_t* qos = dds_create_qos();
  ASSERT_EQ(dds_get_qos(*reader, qos), DDS_RETCODE_OK);
  dds_reliability_kind_t reliability{};
  dds_duration_t blocking = 0;
  ASSERT_TRUE(dds_qget_reliability(qos, &reliability, &blocking));
  EXPECT_EQ(reliability, DDS_RELIABILITY_BEST_EFFORT);
  dds_history_kind_t history{};
  int32_t depth = 0;
  ASSERT_TRUE(dds_qget_history(qos, &history, &depth));
  EXPECT_EQ(history, DDS_HISTORY_KEEP_LAST);
  EXPECT_EQ(depth, 8);
  dds_delete_qos(qos);
  dds_delete(participant);
}

TEST(DdsFleetSubscriberTest, SamplesArriveWithoutPollingOnceARobotIsFoundAndNoneAfterStop) {
  test::use_loopback_dds();
  DdsOptions robot;
  robot.robot = test::unique_robot_name("fleetsubpub");
  robot.domain.domain_id = test::unique_domain_id();
  robot.rviz.ceiling = false;
  auto publisher = DdsPosePublisher::create(robot);
  ASSERT_TRUE(publisher.ok()) << publisher.error().message;
  DdsOptions own = robot;
  own.robot = test::unique_robot_name("fleetsubobs");
  auto observer = DdsPosePublisher::create(own);
  ASSERT_TRUE(observer.ok()) << observer.error().message;
  auto subscriber = DdsFleetSubscriber::create(observer->participant_handle(), own.robot, 8);
  ASSERT_TRUE(subscriber.ok()) << subscriber.error().message;

  CountingSink sink;
  uint64_t seq = 0;
  auto publish = [&] {
    ++seq;
    const PoseRecord pose = test::moving_pose(realtime_ns(), 0.01 * static_cast<double>(seq), seq);
    ASSERT_TRUE(publisher->publish_state(pose).ok());
  };
  // Discovery: the robot's topic is found by poll(), which makes its reader
  // (the observer's own topic is not read).
  ASSERT_TRUE(wait_for(
      [&] {
        publish();
        EXPECT_TRUE(subscriber->poll(20, &sink).ok());
        return subscriber->topics() == 1 && sink.samples() > 0;
      },
      std::chrono::seconds(20)))
      << "the publisher's topic was never found or read; problem: " << sink.problem();
  EXPECT_EQ(sink.robot(), robot.robot);

  // No more polling: 20 samples must still reach the sink (in this one
  // process Cyclone delivers in the writer's thread, between processes in
  // its receive thread; either way, no poll).
  const int before = sink.samples();
  for (int k = 0; k < 20; ++k) {
    publish();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_TRUE(wait_for([&] { return sink.samples() >= before + 20; }, std::chrono::seconds(10)))
      << "without poll() only " << sink.samples() - before << " of 20 samples arrived";

  // After stop_listening() nothing more reaches the sink (it may now go).
  subscriber->stop_listening();
  EXPECT_EQ(subscriber->topics(), 0u);
  const int stopped_at = sink.samples();
  for (int k = 0; k < 10; ++k) publish();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(sink.samples(), stopped_at);
  EXPECT_EQ(sink.problem(), "");
}

}  // namespace
}  // namespace ceilpose
