#pragma once
// The keystore of a secure fleet (SPEC §11): `ceilposectl keys init|add`
// make it, ceilposed and `ceilposectl fleet` check an enclave of it before
// they create a DDS participant. Layout: keystore/keystore_layout.h.
#include <sys/types.h>

#include <ctime>
#include <string>

#include "core/result.h"
#include "ipc/dds/dds_options.h"

namespace ceilpose::keystore {

inline constexpr int kDefaultCaDays = 3650;      // the CA: ten years, as SROS2's
inline constexpr int kDefaultEnclaveDays = 730;  // a robot's identity: two years

struct Validity {
  std::time_t not_before = 0;  // seconds since the epoch
  int days = 0;                // > 0
};

// Creates DIR with a new CA (ECDSA P-256, self-signed) and the signed
// governance document. Refuses a DIR that already has a CA: a new one would
// disown every enclave the old one signed.
Result<void> init_keystore(const std::string& dir, const Validity& validity);

struct EnclaveRequest {
  std::string name;  // a ROS name token: the robot, and its certificate's CN
  Validity validity;
  // An existing enclave is refused unless this is set: replacing it makes a
  // new key and certificate (rotating the robot's key).
  bool replace = false;
};
// Creates enclave DIR/enclaves/NAME: key, certificate, the CA, governance and
// permissions that let it publish rt/NAME/* and subscribe to every robot's
// pose and status.
Result<void> add_enclave(const std::string& dir, const EnclaveRequest& request);

// What ssh checks of a private key, applied to an enclave as `user` would
// use it: the keystore, enclaves and enclave directories and the six files
// belong to `user` or root and no group or other user may write them; the
// private key is readable by nobody else (mode 0600 or less), or, owned by
// root, by its group at most (0640: root:ceilpose for a service user).
// Errors name the path, its mode in octal and its owner.
Result<void> check_enclave_protection(const std::string& dir, const std::string& name, uid_t user);

// The enclave's six files once each is there and good at `now`, protected
// as check_enclave_protection says for this process's effective user: certificates
// parse and are in date, the certificate was issued by the identity CA, the
// key is the certificate's, governance and permissions verify against the
// permissions CA, and the permissions grant the certificate's subject at
// `now`. Errors name the file and the reason.
Result<DdsSecurityFiles> check_enclave(const std::string& dir, const std::string& name,
                                       std::time_t now);

}  // namespace ceilpose::keystore
