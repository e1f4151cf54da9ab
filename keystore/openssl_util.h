#pragma once
// OpenSSL objects owned by unique_ptr, and the few operations on them that
// the keystore's writer and checker share: PEM in and out, S/MIME signing
// and verification, certificate names and dates. Internal to keystore/.
#include <openssl/evp.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>

#include <ctime>
#include <memory>
#include <string>

#include "core/result.h"

namespace ceilpose::keystore {

template <auto Free>
struct OpensslFree {
  template <typename T>
  void operator()(T* p) const {
    Free(p);
  }
};
using PkeyPtr = std::unique_ptr<EVP_PKEY, OpensslFree<EVP_PKEY_free>>;
using X509Ptr = std::unique_ptr<X509, OpensslFree<X509_free>>;
using Pkcs7Ptr = std::unique_ptr<PKCS7, OpensslFree<PKCS7_free>>;
using BioPtr = std::unique_ptr<BIO, OpensslFree<BIO_free_all>>;
using StorePtr = std::unique_ptr<X509_STORE, OpensslFree<X509_STORE_free>>;
using StoreCtxPtr = std::unique_ptr<X509_STORE_CTX, OpensslFree<X509_STORE_CTX_free>>;

// OpenSSL's queued errors as one line (and the queue emptied).
std::string openssl_errors();

// A certificate or private key from a PEM file; errors name the file.
Result<X509Ptr> read_certificate(const std::string& path);
Result<PkeyPtr> read_private_key(const std::string& path);
std::string certificate_pem(X509* cert);
std::string private_key_pem(EVP_PKEY* key);

// A new ECDSA P-256 key (DDS Security's builtin PKI-DH takes RSA-2048 or
// EC prime256v1; EC is what SROS2 makes).
Result<PkeyPtr> new_ec_key();

// An X.509 v3 certificate for subject CN=`common_name`, valid from
// `not_before` for `days`, signed by `issuer` with `issuer_key` (self-signed
// when issuer is null). A CA certificate says CA:TRUE.
struct CertificateRequest {
  std::string common_name;
  EVP_PKEY* subject_key = nullptr;
  X509* issuer = nullptr;
  EVP_PKEY* issuer_key = nullptr;
  bool is_ca = false;
  std::time_t not_before = 0;
  int days = 0;
};
Result<X509Ptr> make_certificate(const CertificateRequest& request);

// `text` signed by `signer` as S/MIME multipart/signed, detached, text mode
// (what `openssl smime -sign -text` and SROS2 make, and what the DDS Security
// plugins verify).
Result<std::string> smime_sign(const std::string& text, X509* signer, EVP_PKEY* signer_key);
// The signed text of an S/MIME document if its signature verifies against
// `ca` (at `now`); `path` names it in errors.
Result<std::string> smime_verify(const std::string& smime, X509* ca, std::time_t now,
                                 const std::string& path);

// "CN=r1" (RFC 2253), as permissions documents name their subject.
std::string subject_name(X509* cert);
// A certificate's validity bounds as seconds since the epoch.
std::time_t not_before(X509* cert);
std::time_t not_after(X509* cert);
// "2026-12-02T17:40:00", UTC: the form of DDS Security documents' dates.
std::string utc_text(std::time_t t);

}  // namespace ceilpose::keystore
