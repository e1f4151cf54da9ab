// The documents of a secure fleet's keystore (SPEC §11) on arbitrary bytes:
// one input is a PEM file, a signed permissions document and a date pair,
// cut by "\n--8<--\n" lines. The PEM is read as a certificate and as a key;
// the signed document is checked against a real CA, first alone, then in
// place of an enclave's permissions.p7s. Invariants: an enclave that passes
// check_enclave with the fuzzed document has a grant for its robot valid now,
// and a grant written for any dates reads back as the same dates.
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <string>
#include <string_view>

#include "fuzz/fuzz_support.h"
#include "keystore/keystore.h"
#include "keystore/keystore_layout.h"
#include "keystore/openssl_util.h"
#include "keystore/security_documents.h"

namespace {

using namespace ceilpose;
using namespace ceilpose::keystore;

constexpr std::time_t kNow = 1'800'000'000;  // 2027-01-15; the keystore's dates are fixed
constexpr std::time_t kLastSecondOf9999 = 253'402'300'799;

struct Keystore {
  std::string dir = "/dev/shm/ceilpose-fuzz-keystore-" + std::to_string(::getpid());
  X509Ptr ca;
  Keystore() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
    const Validity validity{kNow - 86'400, 30};
    if (!init_keystore(dir, validity) || !add_enclave(dir, {"r1", validity, false}))
      fuzz::invariant_broken("fuzz_keystore", "cannot make the keystore in " + dir);
    auto cert = read_certificate(KeystoreLayout{dir}.ca_certificate());
    if (!cert) fuzz::invariant_broken("fuzz_keystore", cert.error().message);
    ca = std::move(cert).value();
  }
  ~Keystore() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

const Keystore& the_keystore() {
  static const Keystore k;
  return k;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const Keystore& ks = the_keystore();
  std::string_view parts[3];
  fuzz::split_input(data, size, parts, 3);

  const std::string pem = fuzz::scratch_dir() + "/file.pem";
  fuzz::write_bytes(pem, parts[0]);
  (void)read_certificate(pem);
  (void)read_private_key(pem);

  // check_enclave verifies the same signature first, so only a document
  // that verifies alone is worth putting in the enclave (it costs 10 ms).
  const std::string document(parts[1]);
  (void)find_grant(document, "CN=r1");
  if (auto text = smime_verify(document, ks.ca.get(), kNow, "fuzz.p7s"); text) {
    const auto grant = find_grant(*text, "CN=r1");
    const DdsSecurityFiles files = KeystoreLayout{ks.dir}.enclave_files("r1");
    std::error_code ec;
    std::filesystem::copy_file(files.permissions, files.permissions + ".good",
                               std::filesystem::copy_options::overwrite_existing, ec);
    fuzz::write_bytes(files.permissions, document);
    if (check_enclave(ks.dir, "r1", kNow) &&
        (!grant || kNow < grant->not_before || kNow > grant->not_after))
      fuzz::invariant_broken("fuzz_keystore", "an enclave passed without a grant valid now");
    std::filesystem::rename(files.permissions + ".good", files.permissions, ec);
  }

  uint64_t dates[2] = {0, 0};
  if (!parts[2].empty())
    std::memcpy(dates, parts[2].data(), std::min(parts[2].size(), sizeof dates));
  const std::time_t from = static_cast<std::time_t>(dates[0] % (kLastSecondOf9999 + 1));
  const std::time_t until = static_cast<std::time_t>(dates[1] % (kLastSecondOf9999 + 1));
  const auto grant = find_grant(permissions_xml("r1", from, until), "CN=r1");
  if (!grant || grant->not_before != from || grant->not_after != until)
    fuzz::invariant_broken("fuzz_keystore", "a grant written for " + std::to_string(from) + ".." +
                                                std::to_string(until) + " read back otherwise");
  return 0;
}
