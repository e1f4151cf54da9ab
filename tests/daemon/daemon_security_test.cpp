// Issue 14: ceilposed in a secure fleet. A keystore made with `ceilposectl
// keys` puts the daemon's poses where only the fleet's enclaves can read them;
// a keystore DDS Security would refuse stops the daemon before it opens the
// camera or publishes anything, naming the file, with exit 6.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <ctime>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/clock.h"
#include "core/exit_codes.h"
#include "core/text_file.h"
#include "ipc/shm/shm_fleet_reader.h"
#include "ipc/shm/shm_fleet_writer.h"
#include "ipc/shm/shm_pose_writer.h"
#include "tests/daemon/daemon_process.h"
#include "tests/ipc/dds/dds_test_env.h"
#include "tests/keystore/test_keystore.h"

namespace ceilpose::test {
namespace {

constexpr int kBoundMs = 30'000;
constexpr std::time_t kDay = 24 * 3600;

class DaemonSecurity : public ::testing::Test {
 protected:
  // ceilposectl fleet, run from here, is on loopback as the daemon is.
  void SetUp() override { use_loopback_dds(); }
  void TearDown() override { remove_daemon_segments(shm_); }

  std::vector<std::string> args(const std::string& keystore, const std::string& robot,
                                std::vector<std::string> extra = {}) const {
    std::vector<std::string> a{"--source", "synthetic", "--shm", shm_,         "--domain",
                               domain_,    "--robot",   robot,   "--keystore", keystore};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  }

  // Runs a daemon that must refuse `keystore` and returns what it logged.
  std::string refused(const std::string& keystore, const std::string& robot = "r1") {
    auto r = run_daemon(args(keystore, robot, {"--duration", "5"}), kBoundMs, env_);
    EXPECT_EQ(r.exit.code, ceilpose::kExitKeystore) << r.err;
    EXPECT_FALSE(shm_exists(shm_)) << "the daemon started its outputs before it refused";
    EXPECT_EQ(r.err.find("capture:"), std::string::npos) << "the camera was opened: " << r.err;
    return r.err;
  }

  const std::map<std::string, std::string> env_{{"CYCLONEDDS_URI", kLoopbackConfig}};
  std::string shm_ = unique_shm_name();
  std::string domain_ = std::to_string(unique_domain_id());
};

RunOutput ctl(const std::vector<std::string>& args) {
  std::vector<std::string> argv{CEILPOSECTL};
  argv.insert(argv.end(), args.begin(), args.end());
  return run_to_end(argv, kBoundMs);
}

// SPEC §11 end to end: the keystore made by ceilposectl keys, the daemon
// configured through dds.security.*, ceilposectl fleet inside and outside.
TEST_F(DaemonSecurity, ASecureDaemonIsSeenByASecureFleetAndNotByAPlainOne) {
  TempDir tmp;
  const std::string ks = tmp.sub("keystore");
  for (const auto& step :
       {std::vector<std::string>{"keys", "init", "--keystore", ks},
        std::vector<std::string>{"keys", "add", "--keystore", ks, "--robot", "secbot"},
        std::vector<std::string>{"keys", "add", "--keystore", ks, "--robot", "monitor"}}) {
    auto made = ctl(step);
    ASSERT_EQ(made.exit_code, 0) << made.err;
  }
  const std::string config = write_temp_file(
      "secure.yaml", "dds:\n  security:\n    keystore: \"" + ks + "\"\n    enclave: secbot\n");
  const std::vector<std::string> daemon_args{"--config", config,  "--source", "synthetic",
                                             "--shm",    shm_,    "--domain", domain_,
                                             "--robot",  "secbot"};
  DaemonProcess daemon(daemon_args, env_);
  daemon.read_error_until("topic rt/secbot/pose", kBoundMs);
  ASSERT_NE(daemon.err().find("DDS Security: enclave secbot of keystore " + ks), std::string::npos)
      << daemon.err();

  // Up to three listens of 6 s: the secure handshakes of every endpoint the
  // daemon has (pose, odom, status, state, TF, ceiling, the fleet's readers)
  // take seconds under ASan on a loaded machine.
  RunOutput secure;
  std::string obj;
  for (int attempt = 0; attempt < 3; ++attempt) {
    secure = ctl({"fleet", "--json", "--duration", "6", "--domain", domain_, "--keystore", ks,
                  "--enclave", "monitor"});
    ASSERT_EQ(secure.exit_code, 0) << secure.err;
    obj = robot_object(secure.out, "secbot");
    if (!obj.empty() && number_field(obj, "samples") > 5.0) break;
  }
  auto plain = ctl({"fleet", "--json", "--duration", "3", "--domain", domain_});
  ASSERT_FALSE(obj.empty()) << secure.out << daemon.err();
  EXPECT_GT(number_field(obj, "samples"), 5.0) << obj;
  EXPECT_TRUE(std::isfinite(number_field(obj, "x_m"))) << obj;
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_NE(plain.out.find("\"robots\":[]"), std::string::npos) << plain.out;

  daemon.signal(SIGTERM);
  auto exit = daemon.wait(5000);
  ASSERT_TRUE(exit.has_value()) << daemon.err();
  EXPECT_EQ(exit->code, ceilpose::kExitOk) << daemon.err();
}

// SPEC §12 on a secure domain: a robot with the fleet's certificate appears
// in another's fleet segment; a robot without one never does, and sees
// nobody itself.
TEST_F(DaemonSecurity, OnlyAuthenticatedRobotsAppearInTheFleet) {
  TempDir tmp;
  const std::string ks = tmp.sub("keystore");
  for (const auto& step :
       {std::vector<std::string>{"keys", "init", "--keystore", ks},
        std::vector<std::string>{"keys", "add", "--keystore", ks, "--robot", "seca"},
        std::vector<std::string>{"keys", "add", "--keystore", ks, "--robot", "secb"}}) {
    auto made = ctl(step);
    ASSERT_EQ(made.exit_code, 0) << made.err;
  }
  // 10 fps: three synthetic cameras render on two cores.
  const std::string config = write_temp_file("fleet.yaml", "capture:\n  fps: 10\n");
  const std::string shm_b = unique_shm_name(), shm_c = unique_shm_name();
  auto daemon_args = [&](const std::string& robot, const std::string& shm, bool secure) {
    std::vector<std::string> a{"--config", config,     "--source", "synthetic", "--shm",
                               shm,        "--domain", domain_,    "--robot",   robot};
    if (secure) a.insert(a.end(), {"--keystore", ks});
    return a;
  };
  DaemonProcess a(daemon_args("seca", shm_, true), env_);
  DaemonProcess b(daemon_args("secb", shm_b, true), env_);
  DaemonProcess c(daemon_args("plainc", shm_c, false), env_);
  std::optional<ShmFleetReader> fleet_a;
  std::vector<shm::FleetRecord> robots(256);
  auto names_in = [&](ShmFleetReader& r) {
    std::set<std::string> names;
    const uint32_t n = r.read(0, robots.data(), 256);
    for (uint32_t i = 0; i < n; ++i) names.insert(robots[i].robot);
    return names;
  };
  const int64_t deadline = monotonic_ns() + int64_t{kBoundMs} * 1'000'000;
  while (monotonic_ns() < deadline) {
    if (!fleet_a) {
      auto r = ShmFleetReader::open(shm_);
      if (r) fleet_a.emplace(std::move(r).value());
    }
    if (fleet_a && names_in(*fleet_a).contains("secb")) break;
    usleep(50'000);
  }
  ASSERT_TRUE(fleet_a && names_in(*fleet_a).contains("secb")) << a.err() << b.err();
  // The plain robot publishes all along; give discovery three more seconds.
  for (int k = 0; k < 30; ++k) {
    EXPECT_FALSE(names_in(*fleet_a).contains("plainc"));
    usleep(100'000);
  }
  EXPECT_EQ(names_in(*fleet_a), std::set<std::string>{"secb"});
  auto fleet_c = ShmFleetReader::open(shm_c);
  ASSERT_TRUE(fleet_c.ok()) << fleet_c.error().message << c.err();
  EXPECT_TRUE(names_in(*fleet_c).empty()) << "a robot without a certificate sees nobody";
  for (DaemonProcess* d : {&a, &b, &c}) d->signal(SIGTERM);
  for (DaemonProcess* d : {&a, &b, &c}) EXPECT_TRUE(d->wait(10'000).has_value());
  for (const std::string& s : {shm_b, shm_c}) remove_daemon_segments(s);
  for (const std::string& s : {shm_, shm_b, shm_c})
    (void)ShmFleetWriter::remove(fleet_segment_name(s));
}

TEST_F(DaemonSecurity, ATamperedPermissionsFileStopsTheDaemonNamingIt) {
  TestKeystore ks{"r1"};
  const std::string path = ks.files("r1").permissions;
  std::string text = read_text_file(path);  // the test helper: whole file or ""
  const size_t at = text.find("<topic>rt/r1/*</topic>");
  ASSERT_NE(at, std::string::npos);
  ASSERT_TRUE(ceilpose::replace_file(path, text.replace(at, 22, "<topic>rt/*/*</topic>")));
  const std::string err = refused(ks.dir());
  EXPECT_NE(err.find(path + ": signature does not verify against the permissions CA"),
            std::string::npos)
      << err;
}

TEST_F(DaemonSecurity, AnExpiredCertificateStopsTheDaemonWithItsDate) {
  TestKeystore ks{};
  ks.add("r1", std::time(nullptr) - 10 * kDay, 3);
  const std::string err = refused(ks.dir());
  EXPECT_NE(err.find(ks.files("r1").certificate + ": certificate expired on "), std::string::npos)
      << err;
}

TEST_F(DaemonSecurity, ACertificateOfAnotherCaStopsTheDaemon) {
  TestKeystore ks{"r1"};
  TestKeystore other{};
  std::filesystem::copy_file(other.layout().ca_certificate(), ks.files("r1").identity_ca,
                             std::filesystem::copy_options::overwrite_existing);
  const std::string err = refused(ks.dir());
  EXPECT_NE(
      err.find(ks.files("r1").certificate + ": certificate was not issued by the identity CA in " +
               ks.files("r1").identity_ca),
      std::string::npos)
      << err;
}

TEST_F(DaemonSecurity, AWorldReadableKeyStopsTheDaemonNamingItsMode) {
  TestKeystore ks{"r1"};
  const std::string key = ks.files("r1").private_key;
  ASSERT_EQ(::chmod(key.c_str(), 0644), 0);
  const std::string err = refused(ks.dir());
  EXPECT_NE(err.find(key + " (mode 0644"), std::string::npos) << err;
}

TEST_F(DaemonSecurity, AMissingFileOrEnclaveStopsTheDaemonNamingIt) {
  TestKeystore ks{"r1"};
  std::filesystem::remove(ks.files("r1").private_key);
  EXPECT_NE(refused(ks.dir()).find(ks.files("r1").private_key + ": cannot read private key"),
            std::string::npos);
  EXPECT_NE(refused(ks.dir(), "r9").find("has no enclave 'r9'"), std::string::npos);
}

// The enclave's files are good, but its permissions are another robot's:
// access control refuses the writer, and nothing is published.
TEST_F(DaemonSecurity, AnEnclaveWhosePermissionsAreAnotherRobotsCannotPublish) {
  TestKeystore ks{"r1", "r2"};
  auto r = run_daemon(args(ks.dir(), "r1", {"--enclave", "r2", "--duration", "5"}), kBoundMs, env_);
  EXPECT_EQ(r.exit.code, ceilpose::kExitKeystore) << r.err;
  EXPECT_NE(r.err.find("rt/r1/pose on domain " + domain_ + ": Not Allowed By Security"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("must allow publishing rt/r1/*"), std::string::npos) << r.err;
}

// --check-config answers what start-up would: the keystore a file names is
// checked too (exit 6), and a good one is valid.
TEST_F(DaemonSecurity, CheckConfigChecksTheKeystoreTheFileNames) {
  TestKeystore ks{"r1"};
  const std::string config = write_temp_file(
      "secure.yaml", "dds:\n  robot_name: r1\n  security:\n    keystore: \"" + ks.dir() + "\"\n");
  auto good = run_daemon({"--check-config", config}, kBoundMs);
  EXPECT_EQ(good.exit.code, ceilpose::kExitOk) << good.err;
  EXPECT_NE(good.out.find(config + ": valid"), std::string::npos) << good.out;
  std::filesystem::remove(ks.files("r1").governance);
  auto bad = run_daemon({"--check-config", config}, kBoundMs);
  EXPECT_EQ(bad.exit.code, ceilpose::kExitKeystore) << bad.err;
  EXPECT_NE(bad.err.find("DDS Security: keystore " + ks.dir() + ": " + ks.files("r1").governance +
                         ": cannot read signed governance document"),
            std::string::npos)
      << bad.err;
}

TEST_F(DaemonSecurity, AnEmptyKeystoreOptionIsAUsageError) {
  auto r = run_daemon({"--keystore", "", "--duration", "1", "--shm", shm_}, kBoundMs);
  EXPECT_EQ(r.exit.code, ceilpose::kExitUsage) << r.err;
}

}  // namespace
}  // namespace ceilpose::test
