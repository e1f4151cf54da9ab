// What `cmake --install` places and what the .deb carries: the same promised
// files (docs/service.md, "Installation").
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/systemd/run_command.h"

namespace ceilpose::test {
namespace {

// Absolute install paths of everything the installation promises, for an
// install with `prefix` (configuration under /etc for /usr, else prefix/etc).
std::vector<std::string> promised_files(const std::string& p) {
  const std::string etc = p == "/usr" ? std::string("/etc") : p + "/etc";
  return {
      p + "/" CEILPOSE_SBINDIR "/ceilposed",
      p + "/" CEILPOSE_BINDIR "/ceilposectl",
      p + "/" CEILPOSE_UNITDIR "/ceilposed.service",
      p + "/" CEILPOSE_SYSUSERSDIR "/ceilpose.conf",
      etc + "/ceilpose/ceilpose.yaml",
      p + "/" CEILPOSE_INCLUDEDIR "/ceilpose/pose_client.h",
      p + "/" CEILPOSE_LIBDIR "/libceilpose_client.so",
      p + "/" CEILPOSE_LIBDIR "/pkgconfig/ceilpose-client.pc",
      p + "/" CEILPOSE_DOCDIR "/service.md",
  };
}

TEST(Install, PlacesEveryPromisedFile) {
  const std::string root = make_temp_dir("install");
  const CommandResult r =
      run_command("DESTDIR=" + root + " cmake --install " CEILPOSE_BINARY_DIR " >/dev/null");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const auto& f : promised_files(CEILPOSE_PREFIX))
    EXPECT_TRUE(std::filesystem::exists(root + f)) << "not installed: " << f;
}

TEST(Install, UnitNamesTheInstalledBinaryAndConfiguration) {
  const std::string root = make_temp_dir("install-unit");
  const CommandResult r = run_command(
      "DESTDIR=" + root + " cmake --install " CEILPOSE_BINARY_DIR " --prefix /usr >/dev/null");
  ASSERT_EQ(r.status, 0) << r.output;
  const CommandResult unit =
      run_command("grep ^ExecStart= " + root + "/usr/" CEILPOSE_UNITDIR "/ceilposed.service");
  EXPECT_EQ(unit.output, "ExecStart=/usr/sbin/ceilposed --config /etc/ceilpose/ceilpose.yaml\n");
  EXPECT_TRUE(std::filesystem::exists(root + "/etc/ceilpose/ceilpose.yaml"));
}

class DebPackage : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!have_tool("dpkg-deb") || !have_tool("cpack")) return;
    dir_ = make_temp_dir("deb");
    build_ =
        run_command("cpack -G DEB --config " CEILPOSE_BINARY_DIR "/CPackConfig.cmake -B " + dir_);
    for (const auto& e : std::filesystem::directory_iterator(dir_))
      if (e.path().extension() == ".deb") deb_ = e.path().string();
  }
  void SetUp() override {
    if (!have_tool("dpkg-deb") || !have_tool("cpack")) GTEST_SKIP() << "dpkg-deb/cpack missing";
    ASSERT_EQ(build_.status, 0) << build_.output;
    ASSERT_FALSE(deb_.empty()) << "cpack made no .deb:\n" << build_.output;
  }
  static std::string dir_;
  static std::string deb_;
  static CommandResult build_;
};
std::string DebPackage::dir_;
std::string DebPackage::deb_;
CommandResult DebPackage::build_;

TEST_F(DebPackage, ContentsListEveryPromisedFile) {
  const CommandResult list = run_command("dpkg-deb -c " + deb_);
  ASSERT_EQ(list.status, 0) << list.output;
  // A system package: prefix /usr, configuration in /etc.
  for (const auto& f : promised_files("/usr")) {
    // A file ends its line; a symbolic link is followed by " -> target".
    const bool listed = list.output.find(" ." + f + "\n") != std::string::npos ||
                        list.output.find(" ." + f + " -> ") != std::string::npos;
    EXPECT_TRUE(listed) << "not in the .deb: " << f;
  }
}

TEST_F(DebPackage, DependsComeFromTheSharedLibraries) {
  const CommandResult depends = run_command("dpkg-deb -f " + deb_ + " Depends");
  ASSERT_EQ(depends.status, 0) << depends.output;
  EXPECT_NE(depends.output.find("libc6"), std::string::npos) << depends.output;
  EXPECT_NE(depends.output.find("libsystemd0"), std::string::npos) << depends.output;
}

TEST_F(DebPackage, PostinstCreatesTheAccountAndConfigIsAConffile) {
  const std::string control = dir_ + "/control";
  const CommandResult r = run_command("dpkg-deb -e " + deb_ + " " + control);
  ASSERT_EQ(r.status, 0) << r.output;
  const CommandResult postinst = run_command("cat " + control + "/postinst");
  EXPECT_NE(postinst.output.find("systemd-sysusers"), std::string::npos) << postinst.output;
  const CommandResult conffiles = run_command("cat " + control + "/conffiles");
  EXPECT_EQ(conffiles.output, "/etc/ceilpose/ceilpose.yaml\n");
}

}  // namespace
}  // namespace ceilpose::test
