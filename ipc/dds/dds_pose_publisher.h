#pragma once
// Publishes a robot's poses as ROS 2 geometry_msgs/msg/PoseWithCovarianceStamped
// on rt/<robot>/pose (ROS topic /<robot>/pose), the same with the filter's
// twist as nav_msgs/msg/Odometry on rt/<robot>/odom, its health as
// ceilpose/msg/Status on rt/<robot>/ceilpose_status and its full state as
// ceilpose/msg/State on rt/<robot>/ceilpose_state (the fleet, SPEC §12),
// all XCDR1 as ROS 2 Humble/Iron expect.
//
// Lifecycle: create() builds participant -> topics -> writers and fails with
// a message naming the step; publish()/publish_status() write; dispose() (or
// the destructor) leaves the domain. Move-only. One thread at a time.
#include <dds/dds.h>

#include <cstdint>
#include <string>
#include <vector>

#include "core/ceiling_layout.h"
#include "core/ceiling_map.h"
#include "core/result.h"
#include "ipc/dds/dds_messages.h"
#include "ipc/dds/dds_options.h"
#include "ipc/dds/dds_participant.h"

namespace ceilpose {

class DdsPosePublisher {
 public:
  static Result<DdsPosePublisher> create(const DdsOptions& options);

  DdsPosePublisher(DdsPosePublisher&&) noexcept = default;
  DdsPosePublisher& operator=(DdsPosePublisher&&) noexcept = default;

  // Per-frame path: no allocation on success. An invalid pose is refused
  // with an error (ROS consumers would take any pose on the topic as a fix):
  // callers publish valid poses only, and the status topic reports no fix.
  Result<void> publish(const DdsPose& pose);
  Result<void> publish_status(const DdsStatus& status);
  // The ceiling for RViz on rt/<robot>/ceiling (transient local: a viewer
  // that starts later still gets it). Once at start; not per frame.
  Result<void> publish_ceiling(const CeilingLayout& layout, const CeilingMap& map);
  // The full state (pose, motion, covariances) on rt/<robot>/ceilpose_state
  // for the other robots' fleet segments; valid poses only, like publish().
  Result<void> publish_state(const PoseRecord& pose);

  // Leaves the domain now: remote readers see the writers go. Idempotent;
  // publishing afterwards fails.
  void dispose();

  const std::string& robot() const { return robot_; }
  const std::string& pose_topic() const { return pose_topic_; }
  const std::string& status_topic() const { return status_topic_; }
  const std::string& odom_topic() const { return odom_topic_; }
  const std::string& state_topic() const { return state_topic_; }
  const std::string& ceiling_topic() const { return ceiling_topic_; }
  // Why TF or the ceiling is not published although configured (their
  // writers are optional: access control of an enclave made before they
  // existed refuses them); empty when all is well.
  const std::string& rviz_problem() const { return rviz_problem_; }
  bool publishes_tf() const { return tf_writer_ > 0; }
  uint32_t domain_id() const { return participant_.domain_id(); }
  // For entities that should share this participant (one participant per
  // process is the cheapest for discovery); 0 after dispose().
  dds_entity_t participant_handle() const { return participant_.handle(); }
  uint64_t published() const { return published_; }
  // Writers of this robot's pose topic in other participants, from the
  // domain's DCPSPublication: > 0 means another process publishes under the
  // same robot name (two robots named alike, or a daemon started twice), and
  // subscribers would see both robots' poses interleaved on one topic.
  // Not per frame: it takes discovery samples (status period).
  Result<size_t> other_pose_writers();

 private:
  DdsPosePublisher() = default;

  DdsParticipant participant_;
  dds_entity_t pose_writer_ = 0;  // children of participant_: deleted with it
  dds_entity_t status_writer_ = 0;
  dds_entity_t odom_writer_ = 0;
  dds_entity_t state_writer_ = 0;
  dds_entity_t tf_writer_ = 0;       // 0: TF off or refused
  dds_entity_t ceiling_writer_ = 0;  // 0: ceiling off or refused
  std::string tf_parent_;
  std::string tf_child_;
  std::string rviz_problem_;
  std::string robot_;
  std::string pose_topic_;
  std::string status_topic_;
  std::string odom_topic_;
  std::string state_topic_;
  std::string ceiling_topic_;
  uint64_t published_ = 0;
  dds_entity_t publication_reader_ = 0;  // DCPSPublication, child of participant_
  dds_guid_t own_guid_{};
  std::vector<dds_instance_handle_t> other_writers_;
};

}  // namespace ceilpose
