#include "ipc/dds/dds_pose_publisher.h"

#include <algorithm>
#include <array>
#include <cstring>

#include "core/clock.h"
#include "ipc/dds/dds_ceiling_markers.h"
#include "ipc/dds/dds_error.h"
#include "ipc/dds/dds_qos.h"

namespace ceilpose {
namespace {

// A reliable writer whose readers stall blocks at most this long in
// dds_write before reporting a timeout: a late pose is worth less than the
// next frame.
constexpr int64_t kMaxBlockingMs = 10;

enum class Durability { kVolatile, kTransientLocal };

Result<dds_entity_t> create_writer(const DdsParticipant& participant,
                                   const dds_topic_descriptor_t* descriptor,
                                   const std::string& topic_name, const DdsOptions& options,
                                   Durability durability = Durability::kVolatile) {
  const std::string where =
      "DDS topic " + topic_name + " on domain " + std::to_string(participant.domain_id());
  const dds_entity_t topic =
      dds_create_topic(participant.handle(), descriptor, topic_name.c_str(), nullptr, nullptr);
  if (topic < 0) return dds_error("cannot create " + where, topic);

  DdsQos qos = make_dds_qos();
  if (options.reliability == DdsReliability::kReliable) {
    dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(kMaxBlockingMs));
  } else {
    dds_qset_reliability(qos.get(), DDS_RELIABILITY_BEST_EFFORT, 0);
  }
  if (durability == Durability::kTransientLocal) {
    // Late joiners (RViz started after the daemon) get the last sample.
    dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 1);
    dds_qset_durability(qos.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
  } else {
    dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, options.history_depth);
    dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  }
  // ROS 2 Humble/Iron and other vendors' ROS readers only speak XCDR1
  // (PLAIN_CDR); say so explicitly rather than rely on Cyclone's choice.
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(qos.get(), 1, &xcdr1);
  const dds_entity_t writer = dds_create_writer(participant.handle(), topic, qos.get(), nullptr);
  if (writer < 0) return dds_error("cannot create a writer for " + where, writer);
  return writer;
}

}  // namespace

Result<DdsPosePublisher> DdsPosePublisher::create(const DdsOptions& options) {
  if (auto ok = validate(options); !ok) return ok.error();
  auto participant = DdsParticipant::create(options.domain);
  if (!participant) return participant.error();

  DdsPosePublisher pub;
  pub.participant_ = std::move(participant.value());
  pub.robot_ = options.robot;
  pub.pose_topic_ = pose_topic_name(options.robot);
  pub.status_topic_ = status_topic_name(options.robot);
  pub.odom_topic_ = odom_topic_name(options.robot);
  pub.state_topic_ = state_topic_name(options.robot);

  auto pose_writer =
      create_writer(pub.participant_, &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc,
                    pub.pose_topic_, options);
  if (!pose_writer) return pose_writer.error();
  pub.pose_writer_ = *pose_writer;
  auto status_writer =
      create_writer(pub.participant_, &ceilpose_msg_dds__Status__desc, pub.status_topic_, options);
  if (!status_writer) return status_writer.error();
  pub.status_writer_ = *status_writer;
  auto odom_writer =
      create_writer(pub.participant_, &nav_msgs_msg_dds__Odometry__desc, pub.odom_topic_, options);
  if (!odom_writer) return odom_writer.error();
  pub.odom_writer_ = *odom_writer;
  auto state_writer =
      create_writer(pub.participant_, &ceilpose_msg_dds__State__desc, pub.state_topic_, options);
  if (!state_writer) return state_writer.error();
  pub.state_writer_ = *state_writer;
  pub.ceiling_topic_ = ceiling_topic_name(options.robot);
  pub.tf_parent_ = options.rviz.tf_parent_frame;
  pub.tf_child_ = tf_child_frame(options);
  // Optional: without them every robot still localizes and shares its pose.
  if (options.rviz.tf) {
    auto tf =
        create_writer(pub.participant_, &tf2_msgs_msg_dds__TFMessage__desc, kTfTopic, options);
    if (tf) {
      pub.tf_writer_ = *tf;
    } else {
      pub.rviz_problem_ = tf.error().message;
    }
  }
  if (options.rviz.ceiling) {
    auto ceiling = create_writer(pub.participant_, &visualization_msgs_msg_dds__MarkerArray__desc,
                                 pub.ceiling_topic_, options, Durability::kTransientLocal);
    if (ceiling) {
      pub.ceiling_writer_ = *ceiling;
    } else {
      pub.rviz_problem_ += (pub.rviz_problem_.empty() ? "" : "; ") + ceiling.error().message;
    }
  }
  pub.publication_reader_ = dds_create_reader(pub.participant_.handle(),
                                              DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  if (pub.publication_reader_ < 0) {
    return dds_error(
        "cannot read DCPSPublication on DDS domain " + std::to_string(pub.participant_.domain_id()),
        pub.publication_reader_);
  }
  if (const dds_return_t rc = dds_get_guid(pub.participant_.handle(), &pub.own_guid_);
      rc != DDS_RETCODE_OK) {
    return dds_error("cannot get the DDS participant's GUID", rc);
  }
  return pub;
}

Result<size_t> DdsPosePublisher::other_pose_writers() {
  if (!participant_.valid()) return make_error("DDS publisher of " + robot_ + " was disposed");
  constexpr int kBatch = 16;
  std::array<void*, kBatch> samples{};
  std::array<dds_sample_info_t, kBatch> infos{};
  for (;;) {
    samples.fill(nullptr);  // Cyclone lends its buffers
    const dds_return_t n =
        dds_take(publication_reader_, samples.data(), infos.data(), kBatch, kBatch);
    if (n < 0) return dds_error("cannot take DCPSPublication samples", n);
    if (n == 0) break;
    for (dds_return_t k = 0; k < n; ++k) {
      const dds_instance_handle_t handle = infos[k].instance_handle;
      auto known = std::find(other_writers_.begin(), other_writers_.end(), handle);
      if (infos[k].instance_state != DDS_IST_ALIVE) {
        if (known != other_writers_.end()) other_writers_.erase(known);
        continue;
      }
      if (!infos[k].valid_data || known != other_writers_.end()) continue;
      const auto* endpoint = static_cast<const dds_builtintopic_endpoint_t*>(samples[k]);
      const bool ours = std::memcmp(&endpoint->participant_key, &own_guid_, sizeof own_guid_) == 0;
      if (!ours && endpoint->topic_name != nullptr && pose_topic_ == endpoint->topic_name)
        other_writers_.push_back(handle);
    }
    if (const dds_return_t rc = dds_return_loan(publication_reader_, samples.data(), n);
        rc != DDS_RETCODE_OK) {
      return dds_error("cannot return DCPSPublication samples", rc);
    }
  }
  return other_writers_.size();
}

Result<void> DdsPosePublisher::publish(const DdsPose& pose) {
  if (!participant_.valid()) return make_error("DDS publisher of " + robot_ + " was disposed");
  // The daemon's DDS sink never passes one; a caller that does has a bug,
  // and ROS consumers would take the pose as a fix.
  if (!pose.valid) return make_error("refusing to publish an invalid pose on " + pose_topic_);
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg;
  to_message(pose, &msg);
  dds_return_t rc = dds_write(pose_writer_, &msg);
  if (rc != DDS_RETCODE_OK) return dds_error("cannot write a pose to " + pose_topic_, rc);
  nav_msgs_msg_dds__Odometry_ odom;
  to_message(pose, &odom);
  rc = dds_write(odom_writer_, &odom);
  if (rc != DDS_RETCODE_OK) return dds_error("cannot write odometry to " + odom_topic_, rc);
  if (tf_writer_ > 0) {
    geometry_msgs_msg_dds__TransformStamped_ transform;
    tf2_msgs_msg_dds__TFMessage_ tf;
    to_message(pose, tf_parent_.c_str(), tf_child_.c_str(), &transform, &tf);
    rc = dds_write(tf_writer_, &tf);
    if (rc != DDS_RETCODE_OK)
      return dds_error(std::string("cannot write a transform to ") + kTfTopic, rc);
  }
  ++published_;
  return {};
}

Result<void> DdsPosePublisher::publish_status(const DdsStatus& status) {
  if (!participant_.valid()) return make_error("DDS publisher of " + robot_ + " was disposed");
  ceilpose_msg_dds__Status_ msg;
  to_message(status, robot_, &msg);
  const dds_return_t rc = dds_write(status_writer_, &msg);
  if (rc != DDS_RETCODE_OK) return dds_error("cannot write a status to " + status_topic_, rc);
  return {};
}

Result<void> DdsPosePublisher::publish_ceiling(const CeilingLayout& layout, const CeilingMap& map) {
  if (!participant_.valid()) return make_error("DDS publisher of " + robot_ + " was disposed");
  if (ceiling_writer_ <= 0) return {};
  const CeilingMarkers markers(layout, map, realtime_ns());
  const dds_return_t rc = dds_write(ceiling_writer_, &markers.message());
  if (rc != DDS_RETCODE_OK) return dds_error("cannot write the ceiling to " + ceiling_topic_, rc);
  return {};
}

Result<void> DdsPosePublisher::publish_state(const PoseRecord& pose) {
  if (!participant_.valid()) return make_error("DDS publisher of " + robot_ + " was disposed");
  if (!pose_is_valid(pose))
    return make_error("refusing to publish an invalid pose on " + state_topic_);
  ceilpose_msg_dds__State_ msg;
  to_message(pose, &msg);
  const dds_return_t rc = dds_write(state_writer_, &msg);
  if (rc != DDS_RETCODE_OK) return dds_error("cannot write a state to " + state_topic_, rc);
  return {};
}

void DdsPosePublisher::dispose() {
  participant_.reset();
  pose_writer_ = 0;
  status_writer_ = 0;
  odom_writer_ = 0;
  state_writer_ = 0;
  tf_writer_ = 0;
  ceiling_writer_ = 0;
  publication_reader_ = 0;
  other_writers_.clear();
}

}  // namespace ceilpose
