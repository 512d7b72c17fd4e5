// Flags of the commands that talk to a localizer server (--server and the streaming
// options of `track --server` and `simulate --server`), and how their output is printed.
#pragma once

#include <string>

#include "clients/grpc/connection.h"
#include "clients/grpc/remote_track.h"
#include "clients/grpc/streamer.h"
#include "clients/io/presence_summary.h"
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

// The streaming options, or INVALID_ARGUMENT naming the flag.
StatusOr<client::RemoteTrackOptions> ParseStreamFlags(const StreamFlags& f);

// Stream output shared by track --server and simulate --server, on stdout:
//   "session=ID token=T backend=cpu resumed=0 ttl_s=60"      (when opened; the token
//                                                             is what `close` needs)
//   "latency_ms p50=... p95=... p99=... max=... (n=...)  rejections=R gaps=G"  (at the end)
//   "no source found in N frames (presence statistic max X, threshold Y)"   (then, when the
//                                                             server tested presence and no
//                                                             frame held a source)
void PrintOpened(const v1::SessionOpened& opened);
void PrintStreamTotals(const client::StreamResult& result);

}  // namespace localizer::cli
