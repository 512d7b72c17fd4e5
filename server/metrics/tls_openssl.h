// OpenSSL pieces of the TLS front (tls_front.h), internal to server/metrics: owning
// deleters, the error queue as text, and the server context made from TlsFrontOptions (TLS
// 1.2 or 1.3, the certificate chain and key, client CAs for mutual TLS).
#pragma once

#include <openssl/ssl.h>
#include <openssl/x509.h>

#include <memory>
#include <string>

#include "engine/core/status.h"
#include "server/metrics/tls_front.h"

namespace localizer::server::metrics {

struct SslCtxFree {
  void operator()(SSL_CTX* ctx) const { SSL_CTX_free(ctx); }
};
struct SslFree {
  void operator()(SSL* ssl) const { SSL_free(ssl); }
};
struct BioFree {
  void operator()(BIO* bio) const { BIO_free(bio); }
};
struct X509Free {
  void operator()(X509* x509) const { X509_free(x509); }
};
struct PkeyFree {
  void operator()(EVP_PKEY* key) const { EVP_PKEY_free(key); }
};

// OpenSSL's first queued error as text ("error:0A00010B:SSL routines::wrong version number"),
// or `fallback`; clears the (per-thread) queue.
std::string OpensslError(const std::string& fallback = "");

// INVALID_ARGUMENT naming what is wrong with the certificate, key or CAs; INTERNAL when
// OpenSSL cannot make a context.
StatusOr<std::unique_ptr<SSL_CTX, SslCtxFree>> MakeTlsServerContext(const TlsFrontOptions& options);

}  // namespace localizer::server::metrics
