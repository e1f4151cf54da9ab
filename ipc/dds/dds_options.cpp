#include "ipc/dds/dds_options.h"

#include <cctype>

namespace ceilpose {
namespace {

// Cyclone 0.10 refuses domain ids above 230 (the port mapping would overflow).
constexpr uint32_t kMaxDomainId = 230;

// Interface names and peer addresses are pasted into XML attributes; rather
// than escape, refuse what no interface name or address contains.
bool is_plain_xml_value(std::string_view value) {
  if (value.empty()) return false;
  for (char c : value) {
    if (c == '<' || c == '>' || c == '&' || c == '"' || c == '\'' || c == ',' ||
        std::isspace(static_cast<unsigned char>(c)) != 0) {
      return false;
    }
  }
  return true;
}

}  // namespace

std::string pose_topic_name(std::string_view robot) { return "rt/" + std::string(robot) + "/pose"; }

std::string status_topic_name(std::string_view robot) {
  return "rt/" + std::string(robot) + "/ceilpose_status";
}

std::string odom_topic_name(std::string_view robot) { return "rt/" + std::string(robot) + "/odom"; }

std::string state_topic_name(std::string_view robot) {
  return "rt/" + std::string(robot) + "/ceilpose_state";
}

std::string ceiling_topic_name(std::string_view robot) {
  return "rt/" + std::string(robot) + "/ceiling";
}

std::string tf_child_frame(const DdsOptions& options) {
  return options.rviz.tf_child_frame.empty() ? options.robot + "/base_link"
                                             : options.rviz.tf_child_frame;
}

std::string robot_from_topic(std::string_view topic, std::string_view suffix) {
  constexpr std::string_view kPrefix = "rt/";
  if (topic.size() <= kPrefix.size() + suffix.size() || !topic.starts_with(kPrefix) ||
      !topic.ends_with(suffix)) {
    return {};
  }
  const std::string_view robot =
      topic.substr(kPrefix.size(), topic.size() - kPrefix.size() - suffix.size());
  return is_valid_ros_name(robot) ? std::string(robot) : std::string();
}

std::string robot_from_pose_topic(std::string_view topic) {
  return robot_from_topic(topic, "/pose");
}

std::string robot_from_state_topic(std::string_view topic) {
  return robot_from_topic(topic, "/ceilpose_state");
}

Result<void> validate(const DdsDomainOptions& options) {
  if (options.domain_id > kMaxDomainId) {
    return make_error("DDS domain id " + std::to_string(options.domain_id) +
                      " is out of range 0.." + std::to_string(kMaxDomainId));
  }
  for (const auto& name : options.interfaces) {
    if (!is_plain_xml_value(name)) {
      return make_error("DDS network interface '" + name + "' is not a valid interface name");
    }
  }
  for (const auto& peer : options.peers) {
    if (!is_plain_xml_value(peer)) {
      return make_error("DDS peer '" + peer + "' is not a valid address");
    }
  }
  return {};
}

Result<void> validate(const DdsOptions& options) {
  if (!is_valid_ros_name(options.robot)) {
    return make_error("robot name '" + options.robot + "' is not " + kRosNameRule + "; e.g. '" +
                      to_ros_name(options.robot) + "'");
  }
  for (const std::string* frame : {&options.rviz.tf_parent_frame, &options.rviz.tf_child_frame}) {
    if (frame->empty()) continue;  // the parent is checked below; an empty child is the default
    if (!is_plain_xml_value(*frame) || frame->size() > 255) {
      return make_error("TF frame '" + *frame +
                        "' must be at most 255 characters without spaces, quotes or <>&,");
    }
  }
  if (options.rviz.tf_parent_frame.empty()) return make_error("TF parent frame must not be empty");
  if (options.history_depth < 1) {
    return make_error("DDS history depth " + std::to_string(options.history_depth) +
                      " must be at least 1");
  }
  return validate(options.domain);
}

std::string cyclone_config_xml(const DdsDomainOptions& options) {
  std::string xml = "<CycloneDDS><Domain id=\"any\"><General>";
  if (!options.interfaces.empty()) {
    xml += "<Interfaces>";
    for (const auto& name : options.interfaces) {
      // Cyclone matches an address or a name given as `name` or `address`;
      // a leading digit means the user gave an address.
      const bool is_address = std::isdigit(static_cast<unsigned char>(name[0])) != 0;
      xml += is_address ? "<NetworkInterface address=\"" : "<NetworkInterface name=\"";
      xml += name + "\"/>";
    }
    xml += "</Interfaces>";
  }
  if (options.allow_multicast.has_value()) {
    xml += *options.allow_multicast ? "<AllowMulticast>default</AllowMulticast>"
                                    : "<AllowMulticast>false</AllowMulticast>";
  }
  xml += "</General>";
  if (!options.peers.empty()) {
    // Unicast discovery reaches a peer's participants through the ports of
    // their participant indices, so each participant needs one.
    xml += "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>" +
           std::to_string(options.max_participants_per_host - 1) +
           "</MaxAutoParticipantIndex><Peers>";
    for (const auto& peer : options.peers) xml += "<Peer address=\"" + peer + "\"/>";
    xml += "</Peers></Discovery>";
  }
  xml += "</Domain></CycloneDDS>";
  return xml;
}

std::vector<std::pair<std::string, std::string>> cyclone_security_properties(
    const DdsSecurityFiles& files, const std::string& plugin_dir) {
  const auto file = [](const std::string& path) { return "file:" + path; };
  const auto plugin = [&](const char* name) { return plugin_dir + "/lib" + name + ".so"; };
  return {
      {"dds.sec.auth.library.path", plugin("dds_security_auth")},
      {"dds.sec.auth.library.init", "init_authentication"},
      {"dds.sec.auth.library.finalize", "finalize_authentication"},
      {"dds.sec.crypto.library.path", plugin("dds_security_crypto")},
      {"dds.sec.crypto.library.init", "init_crypto"},
      {"dds.sec.crypto.library.finalize", "finalize_crypto"},
      {"dds.sec.access.library.path", plugin("dds_security_ac")},
      {"dds.sec.access.library.init", "init_access_control"},
      {"dds.sec.access.library.finalize", "finalize_access_control"},
      {"dds.sec.auth.identity_ca", file(files.identity_ca)},
      {"dds.sec.auth.identity_certificate", file(files.certificate)},
      {"dds.sec.auth.private_key", file(files.private_key)},
      {"dds.sec.access.permissions_ca", file(files.permissions_ca)},
      {"dds.sec.access.governance", file(files.governance)},
      {"dds.sec.access.permissions", file(files.permissions)},
  };
}

const char* cyclone_security_plugin_dir() { return CEILPOSE_DDS_SECURITY_PLUGIN_DIR; }

}  // namespace ceilpose
