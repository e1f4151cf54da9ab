#include "keystore/security_documents.h"

#include <cstdio>

#include "keystore/openssl_util.h"

namespace ceilpose::keystore {
namespace {

std::string domains_xml(const char* indent) {
  const std::string i = indent;
  return i + "<domains>\n" + i + "  <id_range>\n" + i + "    <min>" + std::to_string(kMinDomainId) +
         "</min>\n" + i + "    <max>" + std::to_string(kMaxDomainId) + "</max>\n" + i +
         "  </id_range>\n" + i + "</domains>\n";
}

// The text between <tag> and </tag> from `from` on, trimmed; npos-safe.
std::optional<std::string> element(const std::string& xml, const std::string& tag, size_t from,
                                   size_t until) {
  const std::string open = "<" + tag + ">";
  const size_t b = xml.find(open, from);
  if (b == std::string::npos || b >= until) return std::nullopt;
  const size_t e = xml.find("</" + tag + ">", b);
  if (e == std::string::npos || e > until) return std::nullopt;
  std::string text = xml.substr(b + open.size(), e - b - open.size());
  const auto not_space = text.find_first_not_of(" \t\r\n");
  if (not_space == std::string::npos) return std::string();
  return text.substr(not_space, text.find_last_not_of(" \t\r\n") - not_space + 1);
}

std::optional<std::time_t> parse_utc(const std::string& text) {
  struct tm tm {};
  int consumed = 0;
  if (std::sscanf(text.c_str(), "%4d-%2d-%2dT%2d:%2d:%2d%n", &tm.tm_year, &tm.tm_mon, &tm.tm_mday,
                  &tm.tm_hour, &tm.tm_min, &tm.tm_sec, &consumed) != 6) {
    return std::nullopt;
  }
  const std::string rest = text.substr(static_cast<size_t>(consumed));
  if (!rest.empty() && rest != "Z") return std::nullopt;
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  return timegm(&tm);
}

}  // namespace

std::string governance_xml() {
  return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
         "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
         "xsi:noNamespaceSchemaLocation=\"http://www.omg.org/spec/DDS-SECURITY/20170901/"
         "omg_shared_ca_governance.xsd\">\n"
         "  <domain_access_rules>\n"
         "    <domain_rule>\n" +
         domains_xml("      ") +
         "      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>\n"
         "      <enable_join_access_control>true</enable_join_access_control>\n"
         "      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>\n"
         "      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>\n"
         // No RTPS message signature: every submessage is already authenticated
         // (metadata ENCRYPT, which also refuses a replayed sequence number) and
         // every payload encrypted; the signature added a third check of every
         // sample, 3 % of a core at 50 robots (docs/security.md, docs/fleet.md).
         "      <rtps_protection_kind>NONE</rtps_protection_kind>\n"
         "      <topic_access_rules>\n"
         "        <topic_rule>\n"
         "          <topic_expression>*</topic_expression>\n"
         "          <enable_discovery_protection>true</enable_discovery_protection>\n"
         "          <enable_liveliness_protection>true</enable_liveliness_protection>\n"
         "          <enable_read_access_control>true</enable_read_access_control>\n"
         "          <enable_write_access_control>true</enable_write_access_control>\n"
         "          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>\n"
         "          <data_protection_kind>ENCRYPT</data_protection_kind>\n"
         "        </topic_rule>\n"
         "      </topic_access_rules>\n"
         "    </domain_rule>\n"
         "  </domain_access_rules>\n"
         "</dds>\n";
}

std::string publish_topic_pattern(const std::string& robot) { return "rt/" + robot + "/*"; }

std::vector<std::string> subscribe_topic_patterns() {
  return {"rt/*/pose", "rt/*/ceilpose_status", "rt/*/ceilpose_state"};
}

std::string permissions_xml(const std::string& robot, std::time_t not_before,
                            std::time_t not_after) {
  std::string subscribe;
  for (const auto& pattern : subscribe_topic_patterns()) {
    subscribe += "            <topic>" + pattern + "</topic>\n";
  }
  return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
         "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
         "xsi:noNamespaceSchemaLocation=\"http://www.omg.org/spec/DDS-SECURITY/20170901/"
         "omg_shared_ca_permissions.xsd\">\n"
         "  <permissions>\n"
         "    <grant name=\"" +
         robot +
         "\">\n"
         "      <subject_name>CN=" +
         robot +
         "</subject_name>\n"
         "      <validity>\n"
         "        <not_before>" +
         utc_text(not_before) +
         "</not_before>\n"
         "        <not_after>" +
         utc_text(not_after) +
         "</not_after>\n"
         "      </validity>\n"
         "      <allow_rule>\n" +
         domains_xml("        ") +
         "        <publish>\n"
         "          <topics>\n"
         "            <topic>" +
         publish_topic_pattern(robot) +
         "</topic>\n"
         // ROS has one TF topic for every robot (rt/tf): any robot of the
         // fleet may publish on it. TF is for viewers; controllers read the
         // fleet from rt/<robot>/ceilpose_state, which only <robot> may write.
         "            <topic>rt/tf</topic>\n"
         "          </topics>\n"
         "        </publish>\n"
         "        <subscribe>\n"
         "          <topics>\n" +
         subscribe +
         "          </topics>\n"
         "        </subscribe>\n"
         "      </allow_rule>\n"
         "      <default>DENY</default>\n"
         "    </grant>\n"
         "  </permissions>\n"
         "</dds>\n";
}

std::optional<GrantValidity> find_grant(const std::string& permissions,
                                        const std::string& subject) {
  for (size_t at = permissions.find("<grant"); at != std::string::npos;
       at = permissions.find("<grant", at + 1)) {
    const size_t end = permissions.find("</grant>", at);
    if (end == std::string::npos) break;
    if (element(permissions, "subject_name", at, end) != subject) continue;
    const auto from = element(permissions, "not_before", at, end);
    const auto until = element(permissions, "not_after", at, end);
    const auto from_t = from ? parse_utc(*from) : std::nullopt;
    const auto until_t = until ? parse_utc(*until) : std::nullopt;
    if (!from_t || !until_t) return std::nullopt;
    return GrantValidity{*from_t, *until_t};
  }
  return std::nullopt;
}

}  // namespace ceilpose::keystore
