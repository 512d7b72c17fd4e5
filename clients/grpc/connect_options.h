// How a client reaches a server that wants credentials: a plain struct with no gRPC in it,
// so that code which only fills it from flags (localizer-cli's offline build, which links no
// gRPC: clients/cli/full_cli.h) need not include gRPC's headers. Connect (connection.h)
// reads it.
#pragma once

#include <string>

namespace localizer::client {

// How to reach a server that wants credentials; the CLI flags of the same names
// (--tls-ca, --tls-cert, --tls-key, --auth-token-file) fill it. All empty: plaintext.
struct ConnectOptions {
  std::string tls_ca;           // PEM CA file the server's certificate must chain to; set
                                // (or tls_cert set): TLS. "" with TLS: the system's roots
  std::string tls_cert;         // PEM client certificate chain (mutual TLS); with tls_key
  std::string tls_key;          // PEM private key of tls_cert
  std::string auth_token_file;  // file with the bearer token: its first line that is not
                                // blank or '#'; "ROLE TOKEN" (a line of the server's file)
                                // also works, the last field is the token
  // Not a flag: true gives the channel a TCP connection of its own (a local subchannel
  // pool) instead of sharing one with every channel of the same target and arguments; load
  // generators spread their streams over several connections this way.
  bool own_connection = false;
  bool tls() const { return !tls_ca.empty() || !tls_cert.empty(); }
};

}  // namespace localizer::client
