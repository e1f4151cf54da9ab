#pragma once
// What a DDS participant of ceilpose needs to know: domain, network, QoS and
// the robot name that becomes the ROS namespace of its topics.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/result.h"
#include "core/ros_name.h"

namespace ceilpose {

// The six files of an enclave that the DDS Security plugins read (OMG DDS
// Security 1.1, builtin PKI-DH, Access-Permissions and AES-GCM-GMAC). They
// are given to the participant as QoS properties, so they compose with
// whatever CYCLONEDDS_URI or the explicit domain says about the network.
// keystore/ finds and checks them; here they are only paths.
struct DdsSecurityFiles {
  std::string identity_ca;     // PEM certificate of the identity CA
  std::string certificate;     // PEM certificate of this participant (CN=<enclave>)
  std::string private_key;     // PEM private key matching `certificate`
  std::string permissions_ca;  // PEM certificate that signed governance and permissions
  std::string governance;      // S/MIME signed governance document (.p7s)
  std::string permissions;     // S/MIME signed permissions document (.p7s)
};

// Where the participant lives. With no interfaces, peers or multicast choice
// Cyclone reads its configuration from CYCLONEDDS_URI as usual; otherwise
// ceilpose creates the domain itself from these options alone (CYCLONEDDS_URI
// is then not read for this domain).
struct DdsDomainOptions {
  uint32_t domain_id = 0;               // SPEC §7: --domain, default 0; Cyclone allows 0..230
  std::vector<std::string> interfaces;  // network interface names or addresses, e.g. "eth0", "lo"
  std::vector<std::string> peers;       // unicast discovery peers, e.g. "10.0.0.7", "127.0.0.1"
  // With peers (unicast discovery) every participant on a host needs a
  // participant index, and Cyclone's default allows 10 (index 0..9): the
  // eleventh daemon or tool on a host fails. RTPS port arithmetic allows 120.
  uint32_t max_participants_per_host = 64;
  // Unset keeps Cyclone's default.
  std::optional<bool> allow_multicast;
  // Set: the participant authenticates, is access-controlled and encrypts
  // (DDS Security); unset: plain DDS, as before.
  std::optional<DdsSecurityFiles> security;

  bool needs_explicit_domain() const {
    return !interfaces.empty() || !peers.empty() || allow_multicast.has_value();
  }
};

enum class DdsReliability : uint8_t { kReliable, kBestEffort };

// What RViz needs without glue (SPEC §12): every pose as TF, and the ceiling.
struct DdsRvizOptions {
  bool tf = true;  // rt/tf: parent_frame -> child_frame per pose
  std::string tf_parent_frame = "map";
  std::string tf_child_frame;  // "" = "<robot>/base_link"
  bool ceiling = true;         // rt/<robot>/ceiling, transient local
};

struct DdsOptions {
  // ROS name token: the namespace of the topics rt/<robot>/pose and
  // rt/<robot>/ceilpose_status. Must satisfy is_valid_ros_name().
  std::string robot;
  DdsDomainOptions domain;
  // ROS 2's default profile is reliable, keep-last 10, volatile; a reliable
  // writer serves both reliable and best-effort readers, the reverse is not true.
  DdsReliability reliability = DdsReliability::kReliable;
  int32_t history_depth = 10;  // keep-last depth of the writers, >= 1
  DdsRvizOptions rviz;
};

// is_valid_ros_name() and to_ros_name(): core/ros_name.h.

std::string pose_topic_name(std::string_view robot);    // "rt/<robot>/pose"
std::string status_topic_name(std::string_view robot);  // "rt/<robot>/ceilpose_status"
std::string odom_topic_name(std::string_view robot);    // "rt/<robot>/odom"

// rt/<robot>/ceilpose_state: the full state the fleet keeps (SPEC §12).
std::string state_topic_name(std::string_view robot);
// rt/<robot>/ceiling: the ceiling as visualization_msgs/MarkerArray.
std::string ceiling_topic_name(std::string_view robot);
// ROS's one TF topic, shared by every robot.
inline constexpr char kTfTopic[] = "rt/tf";
// The TF child frame of `options`: tf_child_frame, or "<robot>/base_link".
std::string tf_child_frame(const DdsOptions& options);

// For a DDS topic name rt/<robot><suffix> returns <robot> if it is a valid
// ROS name, else empty.
std::string robot_from_topic(std::string_view topic, std::string_view suffix);
std::string robot_from_pose_topic(std::string_view topic);   // rt/<robot>/pose
std::string robot_from_state_topic(std::string_view topic);  // rt/<robot>/ceilpose_state

// Checks ranges and names, the messages naming the offending option.
Result<void> validate(const DdsDomainOptions& options);
Result<void> validate(const DdsOptions& options);

// The Cyclone XML fragment for the explicit settings of `options`
// (<CycloneDDS><Domain id="any">...), valid for dds_create_domain.
std::string cyclone_config_xml(const DdsDomainOptions& options);

// The participant QoS properties (name, value) that turn on Cyclone's DDS
// Security plugins with `files`; the plugins are loaded from
// `plugin_dir` (Debian installs them outside the linker's path).
std::vector<std::pair<std::string, std::string>> cyclone_security_properties(
    const DdsSecurityFiles& files, const std::string& plugin_dir);

// Where this build found Cyclone's security plugins (CMake, at configure time).
const char* cyclone_security_plugin_dir();

}  // namespace ceilpose
