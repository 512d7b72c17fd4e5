// An HTTPS/1.1 client for the loopback tests, on OpenSSL directly (no curl, no openssl CLI):
// TLS 1.2 or 1.3, the server verified against a CA file and a host name (the certificate's
// SAN), optionally a client certificate (mutual TLS). Also keeps a handshaken connection open
// without a request (IdleTlsConnection), for the tests of idle clients.
#pragma once

#include <netinet/in.h>
#include <openssl/err.h>
#include <openssl/ssl.h>
#include <openssl/x509v3.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <memory>
#include <string>

#include "server/metrics/tls_openssl.h"
#include "tests/server/http_client.h"

namespace localizer::testing {

namespace metrics = ::localizer::server::metrics;

struct TlsClientOptions {
  std::string ca_file;                    // PEM CAs the server must chain to
  std::string cert_file;                  // PEM client certificate ("": none)
  std::string key_file;                   // its key
  std::string server_name = "localhost";  // checked against the server certificate; sent as SNI
  double timeout_s = 5.0;                 // per socket read or write
};

struct HttpsResponse : HttpResponse {
  bool handshake_ok = false;  // the client finished its side of the TLS handshake
  std::string error;          // why not (OpenSSL's reason), or "" when a response came
};

// A TLS connection to 127.0.0.1:port, handshaken (or not: ok() false, error() says why).
class TlsConnection {
 public:
  TlsConnection(int port, const TlsClientOptions& options) {
    ctx_.reset(SSL_CTX_new(TLS_client_method()));
    if (ctx_ == nullptr) {
      error_ = "SSL_CTX_new failed";
      return;
    }
    SSL_CTX_set_min_proto_version(ctx_.get(), TLS1_2_VERSION);
    if (!options.ca_file.empty() && SSL_CTX_load_verify_locations(ctx_.get(), options.ca_file.c_str(), nullptr) != 1) {
      error_ = metrics::OpensslError("cannot load " + options.ca_file);
      return;
    }
    SSL_CTX_set_verify(ctx_.get(), SSL_VERIFY_PEER, nullptr);
    if (!options.cert_file.empty() &&
        (SSL_CTX_use_certificate_chain_file(ctx_.get(), options.cert_file.c_str()) != 1 ||
         SSL_CTX_use_PrivateKey_file(ctx_.get(), options.key_file.c_str(), SSL_FILETYPE_PEM) != 1)) {
      error_ = metrics::OpensslError("cannot load " + options.cert_file);
      return;
    }
    fd_ = ConnectLoopback(port, options.timeout_s);
    if (fd_ < 0) {
      error_ = "cannot connect";
      return;
    }
    ssl_.reset(SSL_new(ctx_.get()));
    SSL_set_fd(ssl_.get(), fd_);
    SSL_set_tlsext_host_name(ssl_.get(), options.server_name.c_str());
    // The name must be in the certificate: an IP address as such, anything else as a DNS name.
    X509_VERIFY_PARAM* param = SSL_get0_param(ssl_.get());
    if (X509_VERIFY_PARAM_set1_ip_asc(param, options.server_name.c_str()) != 1) {
      ERR_clear_error();
      SSL_set1_host(ssl_.get(), options.server_name.c_str());
    }
    ERR_clear_error();
    if (SSL_connect(ssl_.get()) != 1) {
      error_ = metrics::OpensslError("handshake failed");
      return;
    }
    handshaken_ = true;
  }
  ~TlsConnection() {
    ssl_.reset();
    if (fd_ >= 0) close(fd_);
  }
  TlsConnection(const TlsConnection&) = delete;
  TlsConnection& operator=(const TlsConnection&) = delete;

  bool ok() const { return handshaken_; }
  int fd() const { return fd_; }  // the TCP socket, e.g. to poll for the server's close
  const std::string& error() const { return error_; }

  // Sends `request` (all of it); false with error() set when the connection fails.
  bool Send(const std::string& request) {
    if (!handshaken_) return false;
    size_t sent = 0;
    while (sent < request.size()) {
      ERR_clear_error();
      const int n = SSL_write(ssl_.get(), request.data() + sent, static_cast<int>(request.size() - sent));
      if (n <= 0) {
        error_ = metrics::OpensslError("write failed");
        return false;
      }
      sent += static_cast<size_t>(n);
    }
    return true;
  }

  // Reads until the server closes (or fails) and parses what came.
  HttpsResponse Receive() {
    HttpsResponse response;
    response.handshake_ok = handshaken_;
    std::string raw;
    char buffer[16384];
    while (handshaken_) {
      ERR_clear_error();
      const int n = SSL_read(ssl_.get(), buffer, sizeof buffer);
      if (n <= 0) {
        if (raw.empty()) response.error = metrics::OpensslError("no response");
        ERR_clear_error();
        break;
      }
      raw.append(buffer, static_cast<size_t>(n));
    }
    static_cast<HttpResponse&>(response) = ParseHttpResponse(raw);
    if (!handshaken_) response.error = error_;
    if (!response.ok && response.error.empty()) response.error = "no HTTP response";
    return response;
  }

  // Send, then Receive.
  HttpsResponse Exchange(const std::string& request) {
    if (!Send(request)) {
      HttpsResponse response;
      response.handshake_ok = handshaken_;
      response.error = error_;
      return response;
    }
    return Receive();
  }

 private:
  std::unique_ptr<SSL_CTX, metrics::SslCtxFree> ctx_;
  std::unique_ptr<SSL, metrics::SslFree> ssl_;
  int fd_ = -1;
  bool handshaken_ = false;
  std::string error_;
};

inline HttpsResponse HttpsRawRequest(int port, const std::string& request, const TlsClientOptions& options) {
  TlsConnection connection(port, options);
  return connection.Exchange(request);
}

inline HttpsResponse HttpsRequest(int port, const std::string& method, const std::string& path,
                                  const TlsClientOptions& options, const std::string& bearer_token = "") {
  std::string request = method + " " + path + " HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n";
  if (!bearer_token.empty()) request += "Authorization: Bearer " + bearer_token + "\r\n";
  return HttpsRawRequest(port, request + "\r\n", options);
}

}  // namespace localizer::testing
