#include "server/metrics/tls_openssl.h"

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/pem.h>

#include <vector>

namespace localizer::server::metrics {
namespace {

std::unique_ptr<BIO, BioFree> MemoryBio(const std::string& pem) {
  return std::unique_ptr<BIO, BioFree>(BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size())));
}

// Every certificate in `pem`, in order.
std::vector<std::unique_ptr<X509, X509Free>> Certificates(const std::string& pem) {
  std::vector<std::unique_ptr<X509, X509Free>> certificates;
  auto bio = MemoryBio(pem);
  if (bio == nullptr) return certificates;
  while (X509* certificate = PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr)) {
    certificates.emplace_back(certificate);
  }
  ERR_clear_error();  // the end of the text reads as a "no start line" error
  return certificates;
}

}  // namespace

std::string OpensslError(const std::string& fallback) {
  const unsigned long code = ERR_peek_error();
  std::string text = fallback;
  if (code != 0) {
    char buffer[256];
    ERR_error_string_n(code, buffer, sizeof buffer);
    text = buffer;
  }
  ERR_clear_error();
  return text;
}

StatusOr<std::unique_ptr<SSL_CTX, SslCtxFree>> MakeTlsServerContext(const TlsFrontOptions& options) {
  ERR_clear_error();
  std::unique_ptr<SSL_CTX, SslCtxFree> ctx(SSL_CTX_new(TLS_server_method()));
  if (ctx == nullptr) return Internal("cannot make an OpenSSL context: " + OpensslError());
  SSL_CTX_set_min_proto_version(ctx.get(), TLS1_2_VERSION);
  // No client-initiated renegotiation (TLS 1.2; a cheap way to make the server compute).
  SSL_CTX_set_options(ctx.get(), SSL_OP_NO_RENEGOTIATION | SSL_OP_CIPHER_SERVER_PREFERENCE);
  // Partial writes and a write buffer that may move: the relay retries from its own buffer.
  // Record buffers are released while a connection waits, so idle connections cost little.
  SSL_CTX_set_mode(ctx.get(),
                   SSL_MODE_ENABLE_PARTIAL_WRITE | SSL_MODE_ACCEPT_MOVING_WRITE_BUFFER | SSL_MODE_RELEASE_BUFFERS);
  // One request per connection: nothing to resume, so no session cache and no tickets.
  SSL_CTX_set_session_cache_mode(ctx.get(), SSL_SESS_CACHE_OFF);
  SSL_CTX_set_num_tickets(ctx.get(), 0);

  auto chain = Certificates(options.cert_chain_pem);
  if (chain.empty()) return InvalidArgument("TLS certificate chain holds no PEM certificate");
  if (SSL_CTX_use_certificate(ctx.get(), chain.front().get()) != 1) {
    return InvalidArgument("TLS certificate refused by OpenSSL: " + OpensslError());
  }
  for (size_t i = 1; i < chain.size(); ++i) {
    if (SSL_CTX_add1_chain_cert(ctx.get(), chain[i].get()) != 1) {
      return InvalidArgument("TLS intermediate certificate " + std::to_string(i) +
                             " refused by OpenSSL: " + OpensslError());
    }
  }
  auto key_bio = MemoryBio(options.key_pem);
  // An empty passphrase callback result: encrypted keys are refused, not prompted for.
  std::unique_ptr<EVP_PKEY, PkeyFree> key(
      key_bio == nullptr ? nullptr
                         : PEM_read_bio_PrivateKey(
                               key_bio.get(), nullptr, [](char*, int, int, void*) { return 0; }, nullptr));
  if (key == nullptr) {
    return InvalidArgument("TLS key holds no unencrypted PEM private key: " + OpensslError());
  }
  if (SSL_CTX_use_PrivateKey(ctx.get(), key.get()) != 1 || SSL_CTX_check_private_key(ctx.get()) != 1) {
    return InvalidArgument("TLS key is not the key of the certificate: " + OpensslError());
  }

  if (!options.client_ca_pem.empty()) {
    auto cas = Certificates(options.client_ca_pem);
    if (cas.empty()) return InvalidArgument("TLS client CA file holds no PEM certificate");
    X509_STORE* store = SSL_CTX_get_cert_store(ctx.get());
    for (const auto& ca : cas) {
      if (X509_STORE_add_cert(store, ca.get()) != 1 || SSL_CTX_add_client_CA(ctx.get(), ca.get()) != 1) {
        return InvalidArgument("TLS client CA certificate refused by OpenSSL: " + OpensslError());
      }
    }
    SSL_CTX_set_verify(ctx.get(), SSL_VERIFY_PEER | SSL_VERIFY_FAIL_IF_NO_PEER_CERT, nullptr);
  }
  ERR_clear_error();
  return ctx;
}

}  // namespace localizer::server::metrics
