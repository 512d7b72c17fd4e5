// What `track --server` and `simulate --server` share beyond their flags
// (server_flags.h): the streaming flags parsed into client options, and the
// stream's output. Only localizer-cli-full links it (it needs the gRPC client).
#pragma once

#include "clients/cli/server_flags.h"
#include "clients/grpc/remote_track.h"
#include "clients/grpc/streamer.h"
#include "engine/core/status.h"

namespace localizer::cli {

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
