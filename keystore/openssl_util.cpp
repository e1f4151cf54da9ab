#include "keystore/openssl_util.h"

#include <openssl/bn.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/rand.h>
#include <openssl/x509v3.h>

#include "core/text_file.h"

namespace ceilpose::keystore {
namespace {

using BnPtr = std::unique_ptr<BIGNUM, OpensslFree<BN_free>>;
using NamePtr = std::unique_ptr<X509_NAME, OpensslFree<X509_NAME_free>>;

std::string bio_text(BIO* bio) {
  char* data = nullptr;
  const long n = BIO_get_mem_data(bio, &data);
  return n > 0 ? std::string(data, static_cast<size_t>(n)) : std::string();
}

BioPtr memory_bio(const std::string& text) {
  return BioPtr(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())));
}

std::time_t asn1_time_t(const ASN1_TIME* t) {
  struct tm tm {};
  if (ASN1_TIME_to_tm(t, &tm) != 1) return 0;
  return timegm(&tm);
}

Result<void> add_extension(X509* cert, X509* issuer, int nid, const char* value) {
  X509V3_CTX ctx;
  X509V3_set_ctx_nodb(&ctx);
  X509V3_set_ctx(&ctx, issuer, cert, nullptr, nullptr, 0);
  X509_EXTENSION* ext = X509V3_EXT_conf_nid(nullptr, &ctx, nid, value);
  if (ext == nullptr) return make_error("cannot make extension " + std::string(value));
  const int added = X509_add_ext(cert, ext, -1);
  X509_EXTENSION_free(ext);
  if (added != 1) return make_error("cannot add extension " + std::string(value));
  return {};
}

}  // namespace

std::string openssl_errors() {
  std::string text;
  char buf[256];
  while (const unsigned long e = ERR_get_error()) {
    ERR_error_string_n(e, buf, sizeof(buf));
    if (!text.empty()) text += "; ";
    text += buf;
  }
  return text.empty() ? "no detail from OpenSSL" : text;
}

Result<X509Ptr> read_certificate(const std::string& path) {
  auto text = read_text_file(path, "certificate", size_t{1} << 20);
  if (!text) return text.error();
  BioPtr bio = memory_bio(*text);
  X509Ptr cert(PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr));
  if (!cert) return make_error(path + ": not a PEM certificate (" + openssl_errors() + ")");
  return cert;
}

Result<PkeyPtr> read_private_key(const std::string& path) {
  auto text = read_text_file(path, "private key", size_t{1} << 20);
  if (!text) return text.error();
  BioPtr bio = memory_bio(*text);
  // An empty passphrase callback: an encrypted key is an error, not a prompt.
  PkeyPtr key(PEM_read_bio_PrivateKey(
      bio.get(), nullptr, [](char*, int, int, void*) { return 0; }, nullptr));
  if (!key) {
    return make_error(path + ": not an unencrypted PEM private key (" + openssl_errors() + ")");
  }
  return key;
}

std::string certificate_pem(X509* cert) {
  BioPtr bio(BIO_new(BIO_s_mem()));
  PEM_write_bio_X509(bio.get(), cert);
  return bio_text(bio.get());
}

std::string private_key_pem(EVP_PKEY* key) {
  BioPtr bio(BIO_new(BIO_s_mem()));
  PEM_write_bio_PrivateKey(bio.get(), key, nullptr, nullptr, 0, nullptr, nullptr);
  return bio_text(bio.get());
}

Result<PkeyPtr> new_ec_key() {
  PkeyPtr key(EVP_PKEY_Q_keygen(nullptr, nullptr, "EC", "P-256"));
  if (!key) return make_error("cannot generate an EC P-256 key (" + openssl_errors() + ")");
  return key;
}

Result<X509Ptr> make_certificate(const CertificateRequest& r) {
  X509Ptr cert(X509_new());
  const auto fail = [&](const std::string& what) {
    return make_error("cannot make the certificate of CN=" + r.common_name + ": " + what + " (" +
                      openssl_errors() + ")");
  };
  if (!cert || X509_set_version(cert.get(), X509_VERSION_3) != 1) return fail("X509_new");
  // A random positive 63-bit serial: certificates of one CA never share one.
  unsigned char serial_bytes[8];
  if (RAND_bytes(serial_bytes, sizeof(serial_bytes)) != 1) return fail("no random serial");
  serial_bytes[0] &= 0x7f;
  BnPtr serial(BN_bin2bn(serial_bytes, sizeof(serial_bytes), nullptr));
  if (!serial || BN_to_ASN1_INTEGER(serial.get(), X509_get_serialNumber(cert.get())) == nullptr)
    return fail("serial");
  NamePtr name(X509_NAME_new());
  if (!name ||
      X509_NAME_add_entry_by_txt(name.get(), "CN", MBSTRING_UTF8,
                                 reinterpret_cast<const unsigned char*>(r.common_name.c_str()), -1,
                                 -1, 0) != 1 ||
      X509_set_subject_name(cert.get(), name.get()) != 1)
    return fail("subject");
  X509* issuer = r.issuer != nullptr ? r.issuer : cert.get();
  if (X509_set_issuer_name(cert.get(), X509_get_subject_name(issuer)) != 1) return fail("issuer");
  std::time_t start = r.not_before;
  if (X509_time_adj_ex(X509_getm_notBefore(cert.get()), 0, 0, &start) == nullptr ||
      X509_time_adj_ex(X509_getm_notAfter(cert.get()), r.days, 0, &start) == nullptr)
    return fail("validity");
  if (X509_set_pubkey(cert.get(), r.subject_key) != 1) return fail("public key");
  // No key usage on the CA: it signs the governance and permissions as
  // S/MIME too, and OpenSSL's S/MIME purpose check refuses a CA limited to
  // keyCertSign (SROS2's CA has none either).
  for (auto [nid, value] :
       {std::pair{NID_basic_constraints, r.is_ca ? "critical,CA:TRUE" : "CA:FALSE"},
        std::pair{NID_subject_key_identifier, "hash"}}) {
    if (auto ok = add_extension(cert.get(), issuer, nid, value); !ok)
      return fail(ok.error().message);
  }
  if (r.issuer != nullptr) {
    if (auto ok = add_extension(cert.get(), issuer, NID_authority_key_identifier, "keyid:always");
        !ok)
      return fail(ok.error().message);
  }
  EVP_PKEY* signing_key = r.issuer_key != nullptr ? r.issuer_key : r.subject_key;
  if (X509_sign(cert.get(), signing_key, EVP_sha256()) <= 0) return fail("signature");
  return cert;
}

Result<std::string> smime_sign(const std::string& text, X509* signer, EVP_PKEY* signer_key) {
  constexpr int kFlags = PKCS7_DETACHED | PKCS7_TEXT | PKCS7_STREAM;
  BioPtr in = memory_bio(text);
  Pkcs7Ptr p7(PKCS7_sign(signer, signer_key, nullptr, in.get(), kFlags));
  BioPtr out(BIO_new(BIO_s_mem()));
  if (!p7 || !out || SMIME_write_PKCS7(out.get(), p7.get(), in.get(), kFlags) != 1) {
    return make_error("cannot sign as S/MIME (" + openssl_errors() + ")");
  }
  return bio_text(out.get());
}

Result<std::string> smime_verify(const std::string& smime, X509* ca, std::time_t now,
                                 const std::string& path) {
  BioPtr in = memory_bio(smime);
  BIO* content = nullptr;
  Pkcs7Ptr p7(SMIME_read_PKCS7(in.get(), &content));
  BioPtr content_owner(content);
  if (!p7 || content == nullptr) {
    return make_error(path + ": not an S/MIME signed document (" + openssl_errors() + ")");
  }
  StorePtr store(X509_STORE_new());
  if (!store || X509_STORE_add_cert(store.get(), ca) != 1) {
    return make_error(path + ": cannot set up verification (" + openssl_errors() + ")");
  }
  X509_VERIFY_PARAM_set_time(X509_STORE_get0_param(store.get()), now);
  BioPtr out(BIO_new(BIO_s_mem()));
  if (PKCS7_verify(p7.get(), nullptr, store.get(), content, out.get(), PKCS7_TEXT) != 1) {
    return make_error(path + ": signature does not verify against the permissions CA (" +
                      openssl_errors() + "): the file was changed after signing, or signed by " +
                      "another CA");
  }
  return bio_text(out.get());
}

std::string subject_name(X509* cert) {
  BioPtr bio(BIO_new(BIO_s_mem()));
  X509_NAME_print_ex(bio.get(), X509_get_subject_name(cert), 0, XN_FLAG_RFC2253);
  return bio_text(bio.get());
}

std::time_t not_before(X509* cert) { return asn1_time_t(X509_get0_notBefore(cert)); }
std::time_t not_after(X509* cert) { return asn1_time_t(X509_get0_notAfter(cert)); }

std::string utc_text(std::time_t t) {
  struct tm tm {};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%S", &tm);
  return buf;
}

}  // namespace ceilpose::keystore
