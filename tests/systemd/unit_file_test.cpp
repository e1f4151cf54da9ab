// The service unit and the sysusers.d file, checked by systemd's own tools.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>

#include "core/exit_codes.h"
#include "tests/systemd/run_command.h"

namespace ceilpose::test {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Every value a key takes in the [Service] and [Unit] sections.
std::multimap<std::string, std::string> directives(const std::string& text) {
  std::multimap<std::string, std::string> out;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.empty() || line[0] == '#' || line[0] == '[') continue;
    const size_t eq = line.find('=');
    if (eq != std::string::npos) out.emplace(line.substr(0, eq), line.substr(eq + 1));
  }
  return out;
}

std::string value(const std::multimap<std::string, std::string>& d, const std::string& key) {
  auto it = d.find(key);
  return it == d.end() ? std::string("<missing>") : it->second;
}

TEST(ServiceUnit, PassesSystemdAnalyzeVerify) {
  if (!have_tool("systemd-analyze")) GTEST_SKIP() << "systemd-analyze not installed";
  // verify insists that ExecStart exists: point it at the built binary.
  const std::string dir = make_temp_dir("verify");
  std::string unit = read_text(CEILPOSE_UNIT_FILE);
  const size_t exec = unit.find("ExecStart=") + 10;
  unit.replace(exec, unit.find(' ', exec) - exec, CEILPOSED_PATH);
  std::ofstream(dir + "/ceilposed.service") << unit;
  const CommandResult r = run_command("systemd-analyze verify " + dir + "/ceilposed.service");
  EXPECT_EQ(r.status, 0) << r.output;
  // verify exits 0 on unknown keys and bad values too; it must say nothing.
  EXPECT_EQ(r.output, "") << r.output;
}

TEST(ServiceUnit, IsANotifyServiceWithWatchdogAndRestart) {
  const auto d = directives(read_text(CEILPOSE_UNIT_FILE));
  EXPECT_EQ(value(d, "Type"), "notify");
  EXPECT_EQ(value(d, "NotifyAccess"), "main");
  EXPECT_NE(value(d, "WatchdogSec"), "<missing>");
  EXPECT_EQ(value(d, "Restart"), "on-failure");
  // The codes after which retrying cannot help, from the one table.
  EXPECT_EQ(value(d, "RestartPreventExitStatus"), restart_prevent_exit_status());
  EXPECT_NE(value(d, "ExecReload").find("-HUP"), std::string::npos);
}

TEST(ServiceUnit, RunsUnprivilegedWithRealTimeAndCameraAccess) {
  const auto d = directives(read_text(CEILPOSE_UNIT_FILE));
  EXPECT_EQ(value(d, "User"), "ceilpose");
  EXPECT_EQ(value(d, "SupplementaryGroups"), "video");
  EXPECT_NE(value(d, "LimitRTPRIO"), "<missing>");
  EXPECT_EQ(value(d, "LimitMEMLOCK"), "infinity");
  EXPECT_EQ(value(d, "RestrictRealtime"), "no");
  EXPECT_EQ(value(d, "DevicePolicy"), "closed");
  EXPECT_EQ(value(d, "DeviceAllow"), "char-video4linux rw");
}

TEST(ServiceUnit, IsHardenedButKeepsDevShmShared) {
  const auto d = directives(read_text(CEILPOSE_UNIT_FILE));
  EXPECT_EQ(value(d, "ProtectSystem"), "strict");
  EXPECT_EQ(value(d, "ProtectHome"), "yes");
  EXPECT_EQ(value(d, "PrivateTmp"), "yes");
  EXPECT_EQ(value(d, "NoNewPrivileges"), "yes");
  // PrivateDevices=yes would give the service its own /dev/shm.
  EXPECT_EQ(value(d, "PrivateDevices"), "no");
  // RemoveIPC=yes would delete the segment readers rely on to see "stopped".
  EXPECT_EQ(value(d, "RemoveIPC"), "no");
  EXPECT_EQ(value(d, "RestrictAddressFamilies"), "AF_UNIX AF_INET AF_INET6 AF_NETLINK");
}

TEST(ServiceUnit, ExecStartUsesTheInstalledBinaryAndConfig) {
  const auto d = directives(read_text(CEILPOSE_UNIT_FILE));
  EXPECT_EQ(value(d, "ExecStart"),
            std::string(CEILPOSE_PREFIX "/" CEILPOSE_SBINDIR "/ceilposed --config ") +
                CEILPOSE_FULL_SYSCONFDIR + "/ceilpose/ceilpose.yaml");
}

TEST(Sysusers, CreatesTheServiceAccountInTheVideoGroup) {
  if (!have_tool("systemd-sysusers")) GTEST_SKIP() << "systemd-sysusers not installed";
  const std::string root = make_temp_dir("sysusers");
  run_command("mkdir -p " + root + "/etc && touch " + root + "/etc/passwd " + root + "/etc/group " +
              root + "/etc/shadow " + root + "/etc/gshadow && echo 'video:x:44:' > " + root +
              "/etc/group");
  const CommandResult r =
      run_command("systemd-sysusers --root=" + root + " " CEILPOSE_SYSUSERS_FILE);
  if (r.status != 0 && r.output.find("ermission") != std::string::npos)
    GTEST_SKIP() << "systemd-sysusers needs root here: " << r.output;
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string passwd = read_text(root + "/etc/passwd");
  const std::string group = read_text(root + "/etc/group");
  EXPECT_NE(passwd.find("ceilpose:x:"), std::string::npos) << passwd;
  EXPECT_NE(group.find("ceilpose:x:"), std::string::npos) << group;
  EXPECT_NE(group.find("video:x:44:ceilpose"), std::string::npos) << group;
}

}  // namespace
}  // namespace ceilpose::test
