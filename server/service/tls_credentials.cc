#include "server/service/tls_credentials.h"

#include <grpcpp/security/server_credentials.h>
#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <system_error>

namespace localizer::server {
namespace {

std::string Describe(const std::string& flag, const std::string& path) { return flag + " file \"" + path + "\""; }

// Parses the first certificate of `pem`; null when there is none.
X509* FirstCertificate(const std::string& pem) {
  BIO* bio = BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size()));
  if (bio == nullptr) return nullptr;
  X509* cert = PEM_read_bio_X509(bio, nullptr, nullptr, nullptr);
  BIO_free(bio);
  return cert;
}

EVP_PKEY* PrivateKey(const std::string& pem) {
  BIO* bio = BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size()));
  if (bio == nullptr) return nullptr;
  // An empty passphrase callback result: encrypted keys are refused, not prompted for.
  EVP_PKEY* key = PEM_read_bio_PrivateKey(
      bio, nullptr, [](char*, int, int, void*) { return 0; }, nullptr);
  BIO_free(bio);
  return key;
}

}  // namespace

StatusOr<std::string> ReadPemFile(const std::string& flag, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    return InvalidArgument("cannot read " + Describe(flag, path) + ": " + std::generic_category().message(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return InvalidArgument("cannot read " + Describe(flag, path) + ": read error");
  std::string pem = text.str();
  if (pem.find("-----BEGIN ") == std::string::npos) {
    return InvalidArgument(Describe(flag, path) + " is not PEM (no '-----BEGIN' line)");
  }
  return pem;
}

StatusOr<TlsPem> ReadTlsFiles(const std::string& flag_prefix, const std::string& cert_path, const std::string& key_path,
                              const std::string& client_ca_path) {
  const std::string cert_flag = flag_prefix + "-cert";
  const std::string key_flag = flag_prefix + "-key";
  const std::string ca_flag = flag_prefix + "-client-ca";
  TlsPem pem;
  auto cert = ReadPemFile(cert_flag, cert_path);
  if (!cert.ok()) return cert.status();
  pem.cert = std::move(cert).value();
  auto key = ReadPemFile(key_flag, key_path);
  if (!key.ok()) return key.status();
  pem.key = std::move(key).value();

  X509* x509 = FirstCertificate(pem.cert);
  if (x509 == nullptr) {
    ERR_clear_error();
    return InvalidArgument(Describe(cert_flag, cert_path) + " holds no PEM certificate");
  }
  EVP_PKEY* pkey = PrivateKey(pem.key);
  if (pkey == nullptr) {
    X509_free(x509);
    ERR_clear_error();
    return InvalidArgument(Describe(key_flag, key_path) +
                           " holds no unencrypted PEM private key (encrypted keys are not supported)");
  }
  const bool matches = X509_check_private_key(x509, pkey) == 1;
  EVP_PKEY_free(pkey);
  X509_free(x509);
  ERR_clear_error();
  if (!matches) {
    return InvalidArgument(Describe(key_flag, key_path) + " is not the key of the certificate in " +
                           Describe(cert_flag, cert_path));
  }
  if (!client_ca_path.empty()) {
    auto ca = ReadPemFile(ca_flag, client_ca_path);
    if (!ca.ok()) return ca.status();
    X509* first = FirstCertificate(*ca);
    ERR_clear_error();
    if (first == nullptr) return InvalidArgument(Describe(ca_flag, client_ca_path) + " holds no PEM certificate");
    X509_free(first);
    pem.client_ca = std::move(ca).value();
  }
  return pem;
}

StatusOr<std::shared_ptr<grpc::ServerCredentials>> MakeServerCredentials(const ServerOptions& options) {
  if (options.tls_cert.empty()) return grpc::InsecureServerCredentials();
  auto pem = ReadTlsFiles("--tls", options.tls_cert, options.tls_key, options.tls_client_ca);
  if (!pem.ok()) return pem.status();
  grpc::SslServerCredentialsOptions ssl(GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE);
  ssl.pem_key_cert_pairs.push_back({pem->key, pem->cert});
  if (!pem->client_ca.empty()) {
    ssl.pem_root_certs = pem->client_ca;
    ssl.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
  }
  return grpc::SslServerCredentials(ssl);
}

}  // namespace localizer::server
