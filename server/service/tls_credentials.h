// gRPC server credentials from ServerOptions' TLS fields, and the checked PEM texts for the
// HTTPS front (ReadTlsFiles; server/metrics/tls_front.h).
//
//   no tls_cert                 plaintext (grpc::InsecureServerCredentials)
//   tls_cert + tls_key          TLS; clients verify the server against their CA
//   ... + tls_client_ca         mutual TLS: the handshake fails unless the client presents a
//                               certificate that chains to one in tls_client_ca
//
// The files are read and checked here, before gRPC sees them, so that a bad file is a clear
// error instead of a listener that silently fails to start: INVALID_ARGUMENT naming the flag
// and the path for a file that cannot be read, holds no PEM certificate / key, or a key that
// does not belong to the certificate. Minimum protocol: what gRPC's OpenSSL build allows
// (TLS 1.2 and 1.3).
#pragma once

#include <grpcpp/security/server_credentials.h>

#include <memory>
#include <string>

#include "engine/core/status.h"
#include "server/service/server_options.h"

namespace localizer::server {

StatusOr<std::shared_ptr<grpc::ServerCredentials>> MakeServerCredentials(const ServerOptions& options);

// The PEM texts of a TLS identity, read and checked as above.
struct TlsPem {
  std::string cert;       // the certificate chain
  std::string key;        // its private key
  std::string client_ca;  // CA certificates for client certificates; "" when none was given
};

// Reads and checks cert_path, key_path and, unless empty, client_ca_path, given by the flags
// `flag_prefix` + "-cert", "-key", "-client-ca" ("--tls" for gRPC, "--metrics-tls" for
// HTTPS). INVALID_ARGUMENT naming the flag and the path, as MakeServerCredentials.
StatusOr<TlsPem> ReadTlsFiles(const std::string& flag_prefix, const std::string& cert_path, const std::string& key_path,
                              const std::string& client_ca_path);

// The contents of a PEM file given by `flag` (e.g. "--tls-cert"), or INVALID_ARGUMENT.
StatusOr<std::string> ReadPemFile(const std::string& flag, const std::string& path);

}  // namespace localizer::server
