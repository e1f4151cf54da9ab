#pragma once
// The DDS Security documents of a ceilpose fleet (OMG DDS Security 1.1,
// §9.4.1.2 governance and §9.4.1.3 permissions), written as text for the
// writer to sign, and the one thing the checker reads back from permissions.
#include <ctime>
#include <optional>
#include <string>
#include <vector>

namespace ceilpose::keystore {

// Domains the documents cover: every domain Cyclone allows (0..230).
inline constexpr int kMinDomainId = 0;
inline constexpr int kMaxDomainId = 230;

// No unauthenticated participants, join access control, discovery and
// liveliness protected, every topic's data and metadata encrypted and
// access-controlled.
std::string governance_xml();

// The DDS topics robot `robot` may publish: its own, all of them
// ("rt/<robot>/*": pose, odom, status).
std::string publish_topic_pattern(const std::string& robot);
// The DDS topics every enclave may subscribe to: every robot's pose and status.
std::vector<std::string> subscribe_topic_patterns();

// One grant for subject CN=`robot`, valid from `not_before` to `not_after`,
// default DENY.
std::string permissions_xml(const std::string& robot, std::time_t not_before,
                            std::time_t not_after);

struct GrantValidity {
  std::time_t not_before = 0;
  std::time_t not_after = 0;
};
// The validity of the grant whose subject_name is `subject` ("CN=r1"), or
// nullopt when `permissions` has no such grant or its dates do not parse.
std::optional<GrantValidity> find_grant(const std::string& permissions, const std::string& subject);

}  // namespace ceilpose::keystore
