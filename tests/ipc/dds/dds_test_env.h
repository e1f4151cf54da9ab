#pragma once
// Every DDS test runs on loopback only and on a domain of its own, so that
// parallel test processes and other machines never see each other.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

namespace ceilpose::test {

// lo has no multicast: discovery goes to unicast peer 127.0.0.1, which
// reaches the other participants through their participant-index ports.
inline constexpr char kLoopbackConfig[] =
    "<CycloneDDS><Domain id=\"any\"><General><Interfaces><NetworkInterface name=\"lo\"/>"
    "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
    "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>40"
    "</MaxAutoParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>"
    "</Domain></CycloneDDS>";

// Sets CYCLONEDDS_URI for this process and every child it spawns. Call before
// the first participant is created.
inline void use_loopback_dds() { setenv("CYCLONEDDS_URI", kLoopbackConfig, 1); }

// 1..230 from the pid: distinct for concurrently running test processes.
inline uint32_t unique_domain_id() { return 1 + static_cast<uint32_t>(getpid()) % 230; }

inline std::string unique_robot_name(const char* prefix) {
  return std::string(prefix) + std::to_string(getpid());
}

// The JSON object of `robot` in `ceilposectl fleet --json` output, or "".
inline std::string robot_object(const std::string& json, const std::string& robot) {
  const size_t at = json.find("{\"robot\":\"" + robot + "\"");
  if (at == std::string::npos) return {};
  return json.substr(at, json.find('}', at) - at + 1);
}

// A number field of such an object, NaN when absent.
inline double number_field(const std::string& object, const std::string& key) {
  const size_t at = object.find("\"" + key + "\":");
  if (at == std::string::npos) return std::nan("");
  return std::strtod(object.c_str() + at + key.size() + 3, nullptr);
}

}  // namespace ceilpose::test
