#pragma once
// Where each file of a keystore lives (SPEC §11, the SROS2 layout): the one
// place that spells the paths, for the writer, the checker and the docs.
#include <string>

#include "ipc/dds/dds_options.h"

namespace ceilpose::keystore {

struct KeystoreLayout {
  std::string dir;

  std::string ca_certificate() const { return dir + "/public/ca.cert.pem"; }
  std::string ca_private_key() const { return dir + "/private/ca.key.pem"; }
  // The governance document as `keys init` signed it; each enclave gets a copy.
  std::string governance_xml() const { return dir + "/enclaves/governance.xml"; }
  std::string governance_p7s() const { return dir + "/enclaves/governance.p7s"; }
  std::string enclave_dir(const std::string& name) const { return dir + "/enclaves/" + name; }
  // The readable permissions beside their signed form, as SROS2 keeps them.
  std::string permissions_xml(const std::string& name) const {
    return enclave_dir(name) + "/permissions.xml";
  }
  // The six files the DDS Security plugins read for enclave `name`.
  DdsSecurityFiles enclave_files(const std::string& name) const;
};

}  // namespace ceilpose::keystore
