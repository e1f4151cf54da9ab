#include "keystore/keystore_layout.h"

namespace ceilpose::keystore {

DdsSecurityFiles KeystoreLayout::enclave_files(const std::string& name) const {
  const std::string e = enclave_dir(name) + "/";
  return DdsSecurityFiles{
      .identity_ca = e + "identity_ca.cert.pem",
      .certificate = e + "cert.pem",
      .private_key = e + "key.pem",
      .permissions_ca = e + "permissions_ca.cert.pem",
      .governance = e + "governance.p7s",
      .permissions = e + "permissions.p7s",
  };
}

}  // namespace ceilpose::keystore
