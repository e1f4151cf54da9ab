#pragma once
// C++ names for the records of the shared segment. They ARE the C client's
// structs (ipc/include/ceilpose/pose_client.h), so the daemon, ceilposectl and
// C controllers read and write the same bytes; that header holds the
// offsetof/sizeof checks.
#include <cstdint>

#include "ceilpose/pose_client.h"
#include "core/fix_state.h"
#include "core/motion_model.h"
#include "core/positioning_mode.h"
#include "core/refusal.h"

namespace ceilpose {

using PoseRecord = ::ceilpose_pose;
using StatusRecord = ::ceilpose_status;

static_assert(static_cast<int>(PositioningMode::kAuto) == CEILPOSE_MODE_AUTO &&
                  static_cast<int>(PositioningMode::kChangeOfAxes) == CEILPOSE_MODE_AXES &&
                  static_cast<int>(PositioningMode::kBarycentric) == CEILPOSE_MODE_BARYCENTRIC &&
                  static_cast<int>(PositioningMode::kLeastSquares) == CEILPOSE_MODE_LSQ,
              "core/positioning_mode.h and the C client agree");
static_assert(kRefusalCount <= CEILPOSE_REFUSAL_SLOTS, "a status slot for every refusal");

inline constexpr uint32_t kPoseValid = CEILPOSE_POSE_VALID;
inline constexpr uint32_t kPoseFiltered = CEILPOSE_POSE_FILTERED;
inline constexpr uint32_t kPoseCoasting = CEILPOSE_POSE_COASTING;
inline constexpr uint32_t kPoseMotion = CEILPOSE_POSE_MOTION;
static_assert(kMotionStates == CEILPOSE_STATE_SIZE, "core/motion_model.h and the C client agree");

static_assert(static_cast<uint32_t>(FixState::kNone) == CEILPOSE_FIX_NONE &&
                  static_cast<uint32_t>(FixState::kOk) == CEILPOSE_FIX_OK &&
                  static_cast<uint32_t>(FixState::kCoasting) == CEILPOSE_FIX_COASTING &&
                  static_cast<uint32_t>(FixState::kLost) == CEILPOSE_FIX_LOST,
              "core/fix_state.h and the C client agree");

enum class WriterState : uint32_t {
  kStarting = CEILPOSE_STATE_STARTING,
  kRunning = CEILPOSE_STATE_RUNNING,
  kStopped = CEILPOSE_STATE_STOPPED,
};

// Names used by ceilposectl (human and JSON output).
const char* to_string(WriterState state);
// SPEC §5 mode names: auto, axes, barycentric, lsq; "unknown" otherwise.
const char* pose_mode_name(uint8_t mode);

inline bool pose_is_valid(const PoseRecord& p) { return (p.flags & kPoseValid) != 0; }

// Every number of the record (pose, covariance, motion, jerk) is finite.
bool pose_numbers_finite(const PoseRecord& p);
// The record as an output may carry it: unchanged when its numbers are
// finite, otherwise invalid with every number 0 (issue 28: nothing
// non-finite reaches shared memory or DDS).
void make_publishable(PoseRecord* p);

// The filter's motion into the record's motion fields and CEILPOSE_POSE_MOTION
// (cleared, and the fields zeroed, when `motion` is not valid).
void set_pose_motion(PoseRecord* pose, const MotionEstimate& motion);
// The record's motion, at its capture time; not valid without the flag.
MotionEstimate pose_motion(const PoseRecord& pose);

enum class PredictResult { kOk, kNoMotion, kBeyondHorizon };
// `pose` carried to t_mono_ns (ceilpose_client_predict): pose, yaw, rates and
// their covariance at that instant; *out is `pose` unchanged unless kOk.
PredictResult predict_pose(const PoseRecord& pose, int64_t t_mono_ns, PoseRecord* out);
// The same on the record itself (the fleet reader's, no copies); *pose is
// unchanged unless kOk.
PredictResult predict_pose_in_place(PoseRecord* pose, int64_t t_mono_ns);

// Copies `text` into the status record's fixed source field, truncating and
// always NUL-terminating.
void set_status_source(StatusRecord* status, const char* text);

}  // namespace ceilpose
