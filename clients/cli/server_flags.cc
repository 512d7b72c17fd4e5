#include "clients/cli/server_flags.h"

namespace localizer::cli {

void RegisterServerFlag(FlagSet& flags, std::string* server, bool required, client::ConnectOptions* connect) {
  auto& flag = flags.String("server", server, "HOST:PORT",
                            required ? "localizer-server address"
                                     : "run on a localizer-server at this address instead of "
                                       "locally");
  if (required) flag.Required();
  flags.String("tls-ca", &connect->tls_ca, "FILE",
               "with --server: connect over TLS, verifying the server against these PEM CA certificates");
  flags.String("tls-cert", &connect->tls_cert, "FILE",
               "with --server: PEM client certificate for mutual TLS (with --tls-key; implies TLS)");
  flags.String("tls-key", &connect->tls_key, "FILE", "with --server: PEM private key of --tls-cert");
  flags.String("auth-token-file", &connect->auth_token_file, "FILE",
               "with --server: file holding the bearer token sent on every call (first non-'#' line)");
}

void RegisterStreamFlags(FlagSet& flags, StreamFlags* f, const std::string& default_rate) {
  f->rate = default_rate;
  flags.String("rate", &f->rate, "RATE",
               "with --server: realtime (each block sent once its audio has elapsed) | max "
               "(as fast as the server takes them)");
  flags.Int("block-samples", &f->block_samples, "N", "samples", "with --server: samples per channel per block sent");
  flags.String("encoding", &f->encoding, "ENC",
               "with --server: block encoding, float (float32) | pcm16 (16-bit PCM, clipped at "
               "+-1)");
  flags.String("label", &f->label, "TEXT", "with --server: session label shown by `list`");
  flags.String("session-key", &f->session_key, "KEY",
               "with --server: x-localizer-session-key for session-affine proxies (default: "
               "random)");
}

const std::vector<std::string>& StreamFlagNames() {
  static const std::vector<std::string> names = {"rate",   "block-samples", "encoding", "label",          "session-key",
                                                 "tls-ca", "tls-cert",      "tls-key",  "auth-token-file"};
  return names;
}

}  // namespace localizer::cli
