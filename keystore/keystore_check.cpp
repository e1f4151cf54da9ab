// Everything the DDS Security plugins would refuse, found before a
// participant exists: the plugins only say "not allowed" into Cyclone's trace,
// and by then a daemon may be half started.
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>

#include "core/text_file.h"
#include "keystore/keystore.h"
#include "keystore/keystore_layout.h"
#include "keystore/openssl_util.h"
#include "keystore/security_documents.h"

namespace ceilpose::keystore {
namespace {

Result<void> in_date(X509* cert, const std::string& path, std::time_t now) {
  if (now < not_before(cert)) {
    return make_error(path + ": certificate is not valid before " + utc_text(not_before(cert)) +
                      " UTC (now " + utc_text(now) + " UTC; is the clock right?)");
  }
  if (now > not_after(cert)) {
    return make_error(path + ": certificate expired on " + utc_text(not_after(cert)) +
                      " UTC; renew it with 'ceilposectl keys add --force'");
  }
  return {};
}

// `cert` was signed by `ca` (dates are checked on their own, with a clearer
// message).
Result<void> issued_by(X509* cert, const std::string& cert_path, X509* ca,
                       const std::string& ca_path, std::time_t now) {
  StorePtr store(X509_STORE_new());
  StoreCtxPtr ctx(X509_STORE_CTX_new());
  if (!store || !ctx || X509_STORE_add_cert(store.get(), ca) != 1 ||
      X509_STORE_CTX_init(ctx.get(), store.get(), cert, nullptr) != 1) {
    return make_error(cert_path + ": cannot set up verification (" + openssl_errors() + ")");
  }
  X509_STORE_CTX_set_time(ctx.get(), 0, now);
  if (X509_verify_cert(ctx.get()) == 1) return {};
  const int err = X509_STORE_CTX_get_error(ctx.get());
  openssl_errors();  // drop what verification queued
  return make_error(cert_path + ": certificate was not issued by the identity CA in " + ca_path +
                    " (" + X509_verify_cert_error_string(err) +
                    "): the enclave comes from another keystore, or its CA was replaced");
}

std::string octal(unsigned mode) {
  char text[8];
  std::snprintf(text, sizeof text, "%04o", mode & 07777u);
  return text;
}

// `path` belongs to `user` or root and no one else may write it; `private_key`
// adds who may read it.
Result<void> protected_path(const std::string& path, uid_t user, bool private_key) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return {};  // a missing file is named by its reader
  const std::string what =
      path + " (mode " + octal(st.st_mode) + ", owner uid " + std::to_string(st.st_uid) + ")";
  if (st.st_uid != user && st.st_uid != 0) {
    return make_error(what + " belongs to another user (this process runs as uid " +
                      std::to_string(user) + "): whoever owns it can replace the robot's identity");
  }
  if ((st.st_mode & 022u) != 0) {
    return make_error(what + " is writable by its group or by others: anyone could replace " +
                      "the robot's identity; chmod go-w it");
  }
  if (!private_key) return {};
  const unsigned too_open = st.st_uid == 0 && user != 0 ? 037u : 077u;
  if ((st.st_mode & too_open) != 0) {
    return make_error(what + ": the private key is readable by others; chmod " +
                      (too_open == 037u ? "0640" : "0600") + " it (an unprotected key lets " +
                      "anyone on this computer speak as the robot)");
  }
  return {};
}

}  // namespace

Result<void> check_enclave_protection(const std::string& dir, const std::string& name, uid_t user) {
  const KeystoreLayout ks{dir};
  const DdsSecurityFiles files = ks.enclave_files(name);
  for (const std::string& path :
       {dir, dir + "/enclaves", ks.enclave_dir(name), files.identity_ca, files.certificate,
        files.permissions_ca, files.governance, files.permissions}) {
    if (auto ok = protected_path(path, user, false); !ok) return ok;
  }
  return protected_path(files.private_key, user, true);
}

Result<DdsSecurityFiles> check_enclave(const std::string& dir, const std::string& name,
                                       std::time_t now) {
  const KeystoreLayout ks{dir};
  struct stat st {};
  if (::stat(ks.enclave_dir(name).c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    return make_error("keystore " + dir + " has no enclave '" + name + "' (" +
                      ks.enclave_dir(name) + "); make it with 'ceilposectl keys add --keystore " +
                      dir + " --robot " + name + "'");
  }
  const DdsSecurityFiles files = ks.enclave_files(name);
  if (auto ok = check_enclave_protection(dir, name, ::geteuid()); !ok) return ok.error();
  auto identity_ca = read_certificate(files.identity_ca);
  if (!identity_ca) return identity_ca.error();
  auto permissions_ca = read_certificate(files.permissions_ca);
  if (!permissions_ca) return permissions_ca.error();
  auto cert = read_certificate(files.certificate);
  if (!cert) return cert.error();
  auto key = read_private_key(files.private_key);
  if (!key) return key.error();
  auto governance = read_text_file(files.governance, "signed governance document");
  if (!governance) return governance.error();
  auto permissions = read_text_file(files.permissions, "signed permissions document");
  if (!permissions) return permissions.error();

  for (const auto& [c, path] : {std::pair{identity_ca->get(), &files.identity_ca},
                                std::pair{permissions_ca->get(), &files.permissions_ca},
                                std::pair{cert->get(), &files.certificate}}) {
    if (auto ok = in_date(c, *path, now); !ok) return ok.error();
  }
  if (auto ok =
          issued_by(cert->get(), files.certificate, identity_ca->get(), files.identity_ca, now);
      !ok)
    return ok.error();
  if (X509_check_private_key(cert->get(), key->get()) != 1) {
    openssl_errors();
    return make_error(files.private_key + ": private key does not match the certificate " +
                      files.certificate + " (a key from another enclave, or a half-done rotation)");
  }
  if (auto ok = smime_verify(*governance, permissions_ca->get(), now, files.governance); !ok)
    return ok.error();
  auto granted = smime_verify(*permissions, permissions_ca->get(), now, files.permissions);
  if (!granted) return granted.error();
  const std::string subject = subject_name(cert->get());
  const auto grant = find_grant(*granted, subject);
  if (!grant) {
    return make_error(files.permissions + ": no grant for " + subject + ", the subject of " +
                      files.certificate + " (permissions of another enclave?)");
  }
  if (now < grant->not_before || now > grant->not_after) {
    return make_error(files.permissions + ": the grant for " + subject + " is valid from " +
                      utc_text(grant->not_before) + " to " + utc_text(grant->not_after) +
                      " UTC, not now (" + utc_text(now) + " UTC)");
  }
  return files;
}

}  // namespace ceilpose::keystore
