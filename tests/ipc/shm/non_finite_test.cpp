// Issue 28, defect 4: nothing non-finite reaches shared memory, DDS or JSON.
// The daemon's two outputs carry the record pose_record_of makes, which
// passes through make_publishable (tests/daemon/pipeline_worker_test.cpp);
// what a reader prints of a record is pose_json.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "ipc/shm/pose_record.h"
#include "ipc/shm/pose_text.h"

namespace ceilpose {
namespace {

PoseRecord valid_record() {
  PoseRecord p{};
  p.flags = kPoseValid | kPoseFiltered;
  p.x_m = 1.0;
  p.y_m = 2.0;
  p.yaw_rad = 0.5;
  for (int i = 0; i < 3; ++i) p.covariance[i * 4] = 1e-6;
  MotionEstimate m;
  m.valid = true;
  m.state.x = {1.0, 2.0, 0.5, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0};
  for (int i = 0; i < kMotionStates; ++i) m.state.p[i * kMotionStates + i] = 1e-4;
  m.jerk = {100.0, 100.0, 1e4};
  m.horizon_ms = 200.0;
  set_pose_motion(&p, m);
  return p;
}

// Every double of the record, by address, so that each can be spoiled.
std::vector<double*> numbers(PoseRecord* p) {
  std::vector<double*> out{&p->x_m,
                           &p->y_m,
                           &p->yaw_rad,
                           &p->vx_mps,
                           &p->vy_mps,
                           &p->ax_mps2,
                           &p->yaw_rate_radps,
                           &p->ay_mps2,
                           &p->yaw_accel_radps2};
  for (double& v : p->covariance) out.push_back(&v);
  for (double& v : p->state_covariance) out.push_back(&v);
  for (double& v : p->jerk_density) out.push_back(&v);
  return out;
}

bool json_has_non_finite(const std::string& json) {
  for (const char* word : {"nan", "NaN", "inf", "Inf"})
    if (json.find(word) != std::string::npos) return true;
  return false;
}

TEST(NonFinite, AFiniteRecordIsPublishedUnchanged) {
  PoseRecord p = valid_record();
  const PoseRecord before = p;
  make_publishable(&p);
  EXPECT_EQ(std::memcmp(&p, &before, sizeof p), 0);
  EXPECT_TRUE(pose_is_valid(p));
}

TEST(NonFinite, ANonFiniteNumberAnywhereMakesTheRecordNoPoseWithEveryNumberZero) {
  PoseRecord probe{};
  const size_t count = numbers(&probe).size();
  for (size_t k = 0; k < count; ++k)
    for (double bad :
         {std::numeric_limits<double>::quiet_NaN(), -std::numeric_limits<double>::infinity()}) {
      PoseRecord p = valid_record();
      *numbers(&p)[k] = bad;
      make_publishable(&p);
      SCOPED_TRACE("number " + std::to_string(k) + " = " + std::to_string(bad));
      EXPECT_FALSE(pose_is_valid(p));
      EXPECT_EQ(p.flags & kPoseMotion, 0u);
      EXPECT_TRUE(pose_numbers_finite(p));
      for (double* v : numbers(&p)) EXPECT_EQ(*v, 0.0);
    }
}

TEST(NonFinite, PoseJsonShowsARecordWithANonFiniteNumberAsNoPose) {
  PoseRecord p = valid_record();
  p.covariance[4] = std::numeric_limits<double>::quiet_NaN();  // another writer's record
  const std::string json = pose_json(p, p.capture_mono_ns, "");
  EXPECT_FALSE(json_has_non_finite(json)) << json;
  EXPECT_NE(json.find("\"valid\":false"), std::string::npos) << json;
  const std::string good = pose_json(valid_record(), 0, "");
  EXPECT_NE(good.find("\"valid\":true"), std::string::npos) << good;
  EXPECT_FALSE(json_has_non_finite(good)) << good;
}

}  // namespace
}  // namespace ceilpose
