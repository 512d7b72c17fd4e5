// Flags of the commands that talk to a localizer server (--server and the streaming
// options of `track --server` and `simulate --server`). Registering them needs no gRPC, so
// the offline localizer-cli (full_cli.h) lists and checks them as localizer-cli-full does;
// parsing them into client options and printing a stream's output is server_stream.h's.
#pragma once

#include <string>
#include <vector>

#include "clients/grpc/connect_options.h"
#include "engine/core/flags.h"
#include "engine/core/status.h"

namespace localizer::cli {

struct StreamFlags {
  std::string server;              // HOST:PORT; empty: run locally (track, simulate)
  client::ConnectOptions connect;  // --tls-ca, --tls-cert, --tls-key, --auth-token-file
  std::string rate;                // realtime | max
  int block_samples = 4096;
  std::string encoding = "float";
  std::string label;
  std::string session_key;
};

// --server, and how to reach it: --tls-ca, --tls-cert, --tls-key, --auth-token-file (into
// *connect). `required`: for the commands that only talk to a server.
void RegisterServerFlag(FlagSet& flags, std::string* server, bool required, client::ConnectOptions* connect);
// --rate (default `default_rate`), --block-samples, --encoding, --label, --session-key.
void RegisterStreamFlags(FlagSet& flags, StreamFlags* f, const std::string& default_rate);
// The names of the flags RegisterStreamFlags adds and the credential flags, for "only with
// --server" checks.
const std::vector<std::string>& StreamFlagNames();

}  // namespace localizer::cli
