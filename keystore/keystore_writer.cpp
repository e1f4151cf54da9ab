// keys init and keys add: new keys, certificates and signed documents,
// written file by file with replace_file (a reader never sees half a key).
#include <sys/stat.h>

#include <cerrno>
#include <cstring>

#include "core/ros_name.h"
#include "core/text_file.h"
#include "keystore/keystore.h"
#include "keystore/keystore_layout.h"
#include "keystore/openssl_util.h"
#include "keystore/security_documents.h"

namespace ceilpose::keystore {
namespace {

constexpr unsigned kPrivateFileMode = 0600;
constexpr unsigned kPrivateDirMode = 0700;
constexpr unsigned kPublicDirMode = 0755;
constexpr const char* kCaCommonName = "ceilpose keystore CA";

Result<void> make_dir(const std::string& path, unsigned mode) {
  if (::mkdir(path.c_str(), mode) == 0) return {};
  struct stat st {};
  if (errno == EEXIST && ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) return {};
  return make_error(path + ": cannot create directory (" + std::strerror(errno) + ")");
}

bool exists(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0;
}

Result<void> check_validity(const Validity& v) {
  if (v.days <= 0)
    return make_error("validity of " + std::to_string(v.days) + " days: must be > 0");
  return {};
}

}  // namespace

Result<void> init_keystore(const std::string& dir, const Validity& validity) {
  if (auto ok = check_validity(validity); !ok) return ok;
  const KeystoreLayout ks{dir};
  // Any of the CA's files: a certificate alone, or a key whose certificate
  // was moved away, is still the CA every enclave was signed by.
  for (const std::string& ca_file :
       {ks.ca_certificate(), ks.ca_private_key(), ks.governance_p7s()}) {
    if (exists(ca_file)) {
      return make_error("keystore " + dir + " already has a CA (" + ca_file +
                        "): a new CA would disown every enclave the old one signed; use "
                        "'keys add' to add robots, or another directory");
    }
  }
  for (const auto& [path, mode] :
       {std::pair{dir, kPublicDirMode}, std::pair{dir + "/public", kPublicDirMode},
        std::pair{dir + "/private", kPrivateDirMode},
        std::pair{dir + "/enclaves", kPublicDirMode}}) {
    if (auto ok = make_dir(path, mode); !ok) return ok;
  }
  auto key = new_ec_key();
  if (!key) return key.error();
  auto cert = make_certificate({.common_name = kCaCommonName,
                                .subject_key = key->get(),
                                .is_ca = true,
                                .not_before = validity.not_before,
                                .days = validity.days});
  if (!cert) return cert.error();
  const std::string governance = governance_xml();
  auto signed_governance = smime_sign(governance, cert->get(), key->get());
  if (!signed_governance)
    return make_error(ks.governance_p7s() + ": " + signed_governance.error().message);
  // The key first: a CA certificate on disk without its key would block a
  // second init for nothing.
  if (auto ok = replace_file(ks.ca_private_key(), private_key_pem(key->get()), kPrivateFileMode);
      !ok)
    return ok;
  if (auto ok = replace_file(ks.ca_certificate(), certificate_pem(cert->get())); !ok) return ok;
  if (auto ok = replace_file(ks.governance_xml(), governance); !ok) return ok;
  return replace_file(ks.governance_p7s(), *signed_governance);
}

Result<void> add_enclave(const std::string& dir, const EnclaveRequest& request) {
  if (!is_valid_ros_name(request.name)) {
    return make_error("'" + request.name + "' is not a valid robot name for DDS and ROS 2 (" +
                      kRosNameRule + "; e.g. '" + to_ros_name(request.name) + "')");
  }
  if (auto ok = check_validity(request.validity); !ok) return ok;
  const KeystoreLayout ks{dir};
  if (!exists(ks.ca_certificate())) {
    return make_error("keystore " + dir + " has no CA (" + ks.ca_certificate() +
                      "): run 'ceilposectl keys init --keystore " + dir + "' first");
  }
  auto ca = read_certificate(ks.ca_certificate());
  if (!ca) return ca.error();
  auto ca_key = read_private_key(ks.ca_private_key());
  if (!ca_key) return ca_key.error();
  auto governance = read_text_file(ks.governance_p7s(), "signed governance document");
  if (!governance) return governance.error();
  const std::string enclave = ks.enclave_dir(request.name);
  if (exists(enclave) && !request.replace) {
    return make_error("enclave " + enclave +
                      " exists already; --force replaces its key and certificate (rotation)");
  }
  if (auto ok = make_dir(enclave, kPublicDirMode); !ok) return ok;

  auto key = new_ec_key();
  if (!key) return key.error();
  auto cert = make_certificate({.common_name = request.name,
                                .subject_key = key->get(),
                                .issuer = ca->get(),
                                .issuer_key = ca_key->get(),
                                .not_before = request.validity.not_before,
                                .days = request.validity.days});
  if (!cert) return cert.error();
  const std::string permissions =
      permissions_xml(request.name, not_before(cert->get()), not_after(cert->get()));
  const DdsSecurityFiles files = ks.enclave_files(request.name);
  auto signed_permissions = smime_sign(permissions, ca->get(), ca_key->get());
  if (!signed_permissions)
    return make_error(files.permissions + ": " + signed_permissions.error().message);

  const std::string ca_pem = certificate_pem(ca->get());
  if (auto ok = replace_file(files.private_key, private_key_pem(key->get()), kPrivateFileMode); !ok)
    return ok;
  for (const auto& [path, text] :
       {std::pair{&files.certificate, certificate_pem(cert->get())},
        std::pair{&files.identity_ca, ca_pem}, std::pair{&files.permissions_ca, ca_pem},
        std::pair{&files.governance, *governance},
        std::pair{&files.permissions, *signed_permissions}}) {
    if (auto ok = replace_file(*path, text); !ok) return ok;
  }
  return replace_file(ks.permissions_xml(request.name), permissions);
}

}  // namespace ceilpose::keystore
