#include "keystore/keystore.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/text_file.h"
#include "keystore/keystore_layout.h"
#include "tests/keystore/test_keystore.h"
#include "tests/support/child_process.h"

namespace ceilpose::keystore {
namespace {

constexpr std::time_t kDay = 24 * 3600;

std::string slurp(const std::string& path) {
  auto text = read_text_file(path, "test file");
  return text ? *text : std::string();
}

void spit(const std::string& path, const std::string& text) {
  ASSERT_TRUE(replace_file(path, text));
}

unsigned mode_of(const std::string& path) {
  struct stat st {};
  ::stat(path.c_str(), &st);
  return st.st_mode & 07777;
}

class KeystoreTest : public ::testing::Test {
 protected:
  std::string dir() const { return ks_.dir(); }
  KeystoreLayout layout() const { return ks_.layout(); }
  DdsSecurityFiles r1() const { return ks_.files("r1"); }
  std::string check_error(const std::string& enclave, std::time_t at) const {
    auto checked = check_enclave(dir(), enclave, at);
    return checked ? std::string("(no error)") : checked.error().message;
  }

  test::TestKeystore ks_{"r1"};
  std::time_t now_ = std::time(nullptr);
};

TEST_F(KeystoreTest, InitAndAddLayOutTheSros2KeystoreWithPrivateKeysPrivate) {
  const KeystoreLayout ks = layout();
  auto files = check_enclave(dir(), "r1", now_);
  ASSERT_TRUE(files) << files.error().message;
  EXPECT_EQ(files->certificate, dir() + "/enclaves/r1/cert.pem");
  EXPECT_EQ(files->permissions, dir() + "/enclaves/r1/permissions.p7s");
  for (const std::string& path :
       {ks.ca_certificate(), ks.ca_private_key(), files->identity_ca, files->certificate,
        files->private_key, files->permissions_ca, files->governance, files->permissions}) {
    EXPECT_TRUE(std::filesystem::is_regular_file(path)) << path;
  }
  EXPECT_EQ(mode_of(ks.ca_private_key()), 0600u);
  EXPECT_EQ(mode_of(dir() + "/private"), 0700u);
  EXPECT_EQ(mode_of(files->private_key), 0600u);
  EXPECT_EQ(mode_of(files->certificate), 0644u);
  EXPECT_EQ(slurp(files->identity_ca), slurp(ks.ca_certificate()));
  EXPECT_EQ(slurp(files->permissions_ca), slurp(ks.ca_certificate()));
}

// The openssl command is another implementation of X.509 and S/MIME: what it
// accepts, the DDS Security plugins (which use the same formats) read too.
TEST_F(KeystoreTest, TheOpensslCommandVerifiesCertificatesAndSignedDocuments) {
  const KeystoreLayout ks = layout();
  auto verify = test::run_to_end(
      {"/usr/bin/openssl", "verify", "-CAfile", ks.ca_certificate(), r1().certificate}, 10000);
  EXPECT_EQ(verify.exit_code, 0) << verify.err;
  auto subject = test::run_to_end(
      {"/usr/bin/openssl", "x509", "-noout", "-subject", "-in", r1().certificate}, 10000);
  EXPECT_EQ(subject.out, "subject=CN = r1\n");
  auto key = test::run_to_end(
      {"/usr/bin/openssl", "pkey", "-noout", "-text", "-in", r1().private_key}, 10000);
  EXPECT_NE(key.out.find("NIST CURVE: P-256"), std::string::npos) << key.out;
  for (const auto& [signed_path, xml_path] : {std::pair{r1().permissions, ks.permissions_xml("r1")},
                                              std::pair{r1().governance, ks.governance_xml()}}) {
    auto smime = test::run_to_end({"/usr/bin/openssl", "smime", "-verify", "-text", "-CAfile",
                                   ks.ca_certificate(), "-in", signed_path},
                                  10000);
    EXPECT_EQ(smime.exit_code, 0) << signed_path << ": " << smime.err;
    // S/MIME text is canonical, CRLF; what was signed is the file's text.
    std::string text = smime.out;
    std::erase(text, '\r');
    EXPECT_EQ(text, slurp(xml_path)) << signed_path;
  }
}

TEST_F(KeystoreTest, PermissionsLetARobotPublishOnlyItsOwnTopicsAndReadEveryRobotsPose) {
  const std::string xml = slurp(layout().permissions_xml("r1"));
  EXPECT_NE(xml.find("<subject_name>CN=r1</subject_name>"), std::string::npos);
  // Its own topics, and ROS's one TF topic (which every robot shares).
  EXPECT_NE(xml.find("<publish>\n          <topics>\n            <topic>rt/r1/*</topic>\n"
                     "            <topic>rt/tf</topic>\n          </topics>\n        </publish>"),
            std::string::npos)
      << xml;
  EXPECT_NE(xml.find("<topic>rt/*/pose</topic>"), std::string::npos);
  EXPECT_NE(xml.find("<topic>rt/*/ceilpose_status</topic>"), std::string::npos);
  EXPECT_NE(xml.find("<topic>rt/*/ceilpose_state</topic>"), std::string::npos) << "the fleet";
  EXPECT_NE(xml.find("<default>DENY</default>"), std::string::npos);
  const std::string governance = slurp(layout().governance_xml());
  for (const char* rule :
       {"<allow_unauthenticated_participants>false<", "<enable_join_access_control>true<",
        "<discovery_protection_kind>ENCRYPT<", "<liveliness_protection_kind>ENCRYPT<",
        "<metadata_protection_kind>ENCRYPT<", "<data_protection_kind>ENCRYPT<"}) {
    EXPECT_NE(governance.find(rule), std::string::npos) << rule;
  }
}

TEST_F(KeystoreTest, InitRefusesAKeystoreThatHasACa) {
  const std::string ca = slurp(layout().ca_certificate());
  auto again = init_keystore(dir(), {now_, 10});
  ASSERT_FALSE(again);
  EXPECT_NE(again.error().message.find("already has a CA (" + layout().ca_certificate()),
            std::string::npos)
      << again.error().message;
  EXPECT_EQ(slurp(layout().ca_certificate()), ca);
}

// Issue 28, defect 1: with only the CA's certificate moved away, init made a
// new CA key over the old one and every enclave was orphaned.
TEST_F(KeystoreTest, InitRefusesWhenAnyCaFileIsLeftAndKeepsTheKey) {
  const std::string key = slurp(layout().ca_private_key());
  ASSERT_EQ(std::remove(layout().ca_certificate().c_str()), 0);
  auto again = init_keystore(dir(), {now_, 10});
  ASSERT_FALSE(again);
  EXPECT_NE(again.error().message.find("already has a CA (" + layout().ca_private_key()),
            std::string::npos)
      << again.error().message;
  EXPECT_EQ(slurp(layout().ca_private_key()), key);
}

TEST_F(KeystoreTest, AddRefusesANameThatIsNotARosNameAndAKeystoreWithoutCa) {
  auto dashed = add_enclave(dir(), {.name = "my-robot", .validity = {now_, 10}});
  ASSERT_FALSE(dashed);
  EXPECT_NE(dashed.error().message.find("'my-robot' is not a valid robot name"), std::string::npos);
  EXPECT_NE(dashed.error().message.find("'my_robot'"), std::string::npos);
  for (const char* bad : {"", "1robot", "a/b", "a__b"}) {
    EXPECT_FALSE(add_enclave(dir(), {.name = bad, .validity = {now_, 10}})) << bad;
  }
  auto no_ca = add_enclave(ks_.sibling("empty"), {.name = "r1", .validity = {now_, 10}});
  ASSERT_FALSE(no_ca);
  EXPECT_NE(no_ca.error().message.find("has no CA"), std::string::npos);
  EXPECT_NE(no_ca.error().message.find("keys init --keystore"), std::string::npos);
}

// Issue 28 #18: one length rule for robot names (63 characters: a
// certificate's CN holds 64, the fleet segment's name field 63 and a NUL);
// a name one longer is refused before anything is written, so a retry with
// a good name is not told the enclave exists.
TEST_F(KeystoreTest, ARobotNameOverTheLengthLimitIsRefusedLeavingNothingBehind) {
  const std::string longest(63, 'a'), too_long(64, 'a');
  auto refused = add_enclave(dir(), {.name = too_long, .validity = {now_, 10}});
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("at most 63 characters"), std::string::npos)
      << refused.error().message;
  EXPECT_FALSE(std::filesystem::exists(layout().enclave_dir(too_long)));
  auto made = add_enclave(dir(), {.name = longest, .validity = {now_, 10}});
  EXPECT_TRUE(made) << made.error().message;
}

TEST_F(KeystoreTest, AnExistingEnclaveIsReplacedOnlyWhenAsked) {
  const std::string cert = slurp(r1().certificate);
  auto again = add_enclave(dir(), {.name = "r1", .validity = {now_, 10}});
  ASSERT_FALSE(again);
  EXPECT_NE(again.error().message.find("exists already; --force"), std::string::npos);
  EXPECT_EQ(slurp(r1().certificate), cert);
  ASSERT_TRUE(add_enclave(dir(), {.name = "r1", .validity = {now_, 10}, .replace = true}));
  EXPECT_NE(slurp(r1().certificate), cert);
  EXPECT_TRUE(check_enclave(dir(), "r1", now_));
}

TEST_F(KeystoreTest, AMissingEnclaveOrFileIsNamed) {
  EXPECT_NE(check_error("r9", now_).find("has no enclave 'r9'"), std::string::npos);
  std::filesystem::remove(r1().permissions_ca);
  EXPECT_NE(check_error("r1", now_).find(r1().permissions_ca + ": cannot read certificate"),
            std::string::npos)
      << check_error("r1", now_);
}

// As ssh treats ~/.ssh: a key others can read, or a directory others can
// write, is refused with its path and mode before any participant exists.
TEST_F(KeystoreTest, AWorldReadablePrivateKeyIsRefusedWithItsMode) {
  ASSERT_EQ(::chmod(r1().private_key.c_str(), 0644), 0);
  const std::string error = check_error("r1", now_);
  EXPECT_NE(error.find(r1().private_key + " (mode 0644"), std::string::npos) << error;
  EXPECT_NE(error.find("readable by others; chmod 0600"), std::string::npos) << error;
}

TEST_F(KeystoreTest, AWorldWritableKeystoreDirectoryIsRefusedWithItsMode) {
  for (const std::string& path : {dir() + "/enclaves", layout().enclave_dir("r1"), dir()}) {
    ASSERT_EQ(::chmod(path.c_str(), 0777), 0);
    const std::string error = check_error("r1", now_);
    EXPECT_NE(error.find(path + " (mode 0777"), std::string::npos) << error;
    EXPECT_NE(error.find("writable by its group or by others"), std::string::npos) << error;
    ASSERT_EQ(::chmod(path.c_str(), 0755), 0);
  }
  EXPECT_EQ(check_error("r1", now_), "(no error)");
}

TEST_F(KeystoreTest, AnEnclaveOwnedByAnotherUserIsRefused) {
  const std::string enclave = layout().enclave_dir("r1");
  std::string error;
  if (::geteuid() == 0) {  // root may give the enclave away for real
    ASSERT_EQ(::chown(enclave.c_str(), 4242, 4242), 0);
    error = check_error("r1", now_);
  } else {  // otherwise the check runs as if this were another user's process
    auto ok = check_enclave_protection(dir(), "r1", ::geteuid() + 1);
    error = ok ? std::string("(no error)") : ok.error().message;
  }
  EXPECT_NE(error.find("belongs to another user"), std::string::npos) << error;
}

// A service user reads a root-owned key through its group (root:ceilpose
// 0640), as PostgreSQL allows; others may not read it even then.
TEST_F(KeystoreTest, ARootOwnedKeyMayBeReadByItsGroupOnly) {
  ASSERT_EQ(::chmod(r1().private_key.c_str(), 0640), 0);
  const uid_t service_user = 4242;
  if (::geteuid() == 0) {
    EXPECT_TRUE(check_enclave_protection(dir(), "r1", service_user));
    ASSERT_EQ(::chmod(r1().private_key.c_str(), 0644), 0);
    auto ok = check_enclave_protection(dir(), "r1", service_user);
    ASSERT_FALSE(ok);
    EXPECT_NE(ok.error().message.find("chmod 0640"), std::string::npos) << ok.error().message;
  } else {  // its owner, not root, may not share it with its group
    const std::string error = check_error("r1", now_);
    EXPECT_NE(error.find(r1().private_key + " (mode 0640"), std::string::npos) << error;
  }
}

TEST_F(KeystoreTest, ATamperedPermissionsDocumentFailsItsSignature) {
  std::string p7s = slurp(r1().permissions);
  const size_t at = p7s.find("<topic>rt/r1/*</topic>");
  ASSERT_NE(at, std::string::npos);
  p7s.replace(at, 22, "<topic>rt/*/*</topic>");  // publish as every robot
  spit(r1().permissions, p7s);
  const std::string error = check_error("r1", now_);
  EXPECT_NE(error.find(r1().permissions + ": signature does not verify"), std::string::npos)
      << error;
}

TEST_F(KeystoreTest, ATamperedGovernanceDocumentFailsItsSignature) {
  std::string p7s = slurp(r1().governance);
  const size_t at = p7s.find("<allow_unauthenticated_participants>false");
  ASSERT_NE(at, std::string::npos);
  p7s.replace(at, 41, "<allow_unauthenticated_participants>true ");
  spit(r1().governance, p7s);
  EXPECT_NE(check_error("r1", now_).find(r1().governance + ": signature does not verify"),
            std::string::npos);
}

TEST_F(KeystoreTest, AnExpiredOrNotYetValidCertificateIsRefusedWithItsDate) {
  ASSERT_TRUE(add_enclave(dir(), {.name = "old", .validity = {now_ - 10 * kDay, 2}}));
  const std::string expired = check_error("old", now_);
  EXPECT_NE(expired.find(layout().enclave_files("old").certificate + ": certificate expired on "),
            std::string::npos)
      << expired;
  // The same enclave was good while it was in date.
  EXPECT_TRUE(check_enclave(dir(), "old", now_ - 9 * kDay));
  EXPECT_NE(check_error("r1", now_ - kDay).find("certificate is not valid before"),
            std::string::npos);
}

TEST_F(KeystoreTest, AnEnclaveOfAnotherKeystoreIsNotIssuedByItsCa) {
  const std::string other = ks_.sibling("other");
  ASSERT_TRUE(init_keystore(other, {now_, 100}));
  // The robot keeps its certificate but is handed another fleet's CA.
  std::filesystem::copy_file(KeystoreLayout{other}.ca_certificate(), r1().identity_ca,
                             std::filesystem::copy_options::overwrite_existing);
  const std::string error = check_error("r1", now_);
  EXPECT_NE(error.find(r1().certificate + ": certificate was not issued by the identity CA in " +
                       r1().identity_ca),
            std::string::npos)
      << error;
  // And signed documents of another CA do not verify against this one.
  ASSERT_TRUE(add_enclave(other, {.name = "r1", .validity = {now_, 10}}));
  ASSERT_TRUE(add_enclave(dir(), {.name = "r1", .validity = {now_, 10}, .replace = true}));
  std::filesystem::copy_file(KeystoreLayout{other}.enclave_files("r1").permissions,
                             r1().permissions, std::filesystem::copy_options::overwrite_existing);
  EXPECT_NE(check_error("r1", now_).find(r1().permissions + ": signature does not verify"),
            std::string::npos);
}

TEST_F(KeystoreTest, AKeyThatIsNotTheCertificatesIsRefused) {
  ASSERT_TRUE(add_enclave(dir(), {.name = "r2", .validity = {now_, 10}}));
  std::filesystem::copy_file(layout().enclave_files("r2").private_key, r1().private_key,
                             std::filesystem::copy_options::overwrite_existing);
  EXPECT_NE(check_error("r1", now_)
                .find(r1().private_key + ": private key does not match the certificate"),
            std::string::npos);
}

TEST_F(KeystoreTest, PermissionsOfAnotherRobotGrantNothingToThisOne) {
  ASSERT_TRUE(add_enclave(dir(), {.name = "r2", .validity = {now_, 10}}));
  std::filesystem::copy_file(layout().enclave_files("r2").permissions, r1().permissions,
                             std::filesystem::copy_options::overwrite_existing);
  EXPECT_NE(check_error("r1", now_).find(r1().permissions + ": no grant for CN=r1"),
            std::string::npos);
}

TEST_F(KeystoreTest, ValidityMustBePositive) {
  auto zero = add_enclave(dir(), {.name = "r3", .validity = {now_, 0}});
  ASSERT_FALSE(zero);
  EXPECT_NE(zero.error().message.find("must be > 0"), std::string::npos);
}

}  // namespace
}  // namespace ceilpose::keystore
