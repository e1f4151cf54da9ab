#include "daemon/pose_record_of.h"

#include <algorithm>

namespace ceilpose::daemon {

PoseRecord pose_record_of(const Localization& loc, int64_t real_minus_mono_ns) {
  const PoseEstimate& out = loc.published;
  PoseRecord rec{};
  rec.capture_mono_ns = loc.frame.timestamp_ns;
  rec.capture_real_ns = loc.frame.timestamp_ns + real_minus_mono_ns;
  rec.x_m = out.pose.x_m;
  rec.y_m = out.pose.y_m;
  rec.yaw_rad = out.pose.yaw_rad;
  std::copy(out.covariance.begin(), out.covariance.end(), rec.covariance);
  rec.flags = (out.valid ? kPoseValid : 0u) | (loc.filtered ? kPoseFiltered : 0u) |
              (loc.coasting() ? kPoseCoasting : 0u);
  rec.mode = static_cast<uint8_t>(out.mode);
  rec.markers = static_cast<uint16_t>(out.markers);
  rec.refusal = static_cast<uint8_t>(out.refusal);
  set_pose_motion(&rec, loc.motion);
  make_publishable(&rec);
  return rec;
}

}  // namespace ceilpose::daemon
