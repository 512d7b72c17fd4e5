// `localizer-cli track --server`: a recording streamed through a server session into
// estimates.csv, the remote twin of io::RunTrack (clients/io/track_runner.h), kept in a
// library so that tests run exactly the code the command runs.
//
// Same config: the recording is opened and the session config built by io::PrepareTrack,
// as RunTrack does, and sent with every field explicit (wire::ConfigToProto), except
// max_block_samples, left 0 for the server's own limit (it only bounds block size). The
// server runs the same engine, so with the cpu backend on both sides every estimate's
// numbers (state, covariance, t_s, pairs, ...) equal RunTrack's bit for bit; only the stage
// times differ. `sequence` (the completing block) also matches when RunTrack's block_s
// is block_samples / sample_rate_hz. estimates.csv is written with the same writer.
#pragma once

#include <grpcpp/channel.h>

#include <functional>
#include <memory>
#include <string>

#include "clients/grpc/streamer.h"
#include "clients/grpc/track_stream.h"
#include "clients/io/track_runner.h"
#include "localizer/v1/localizer.pb.h"

namespace localizer::client {

struct RemoteTrackOptions {
  std::string label;             // shown by ListSessions
  std::string session_key;       // x-localizer-session-key; empty: a random one
  int64_t block_samples = 4096;  // per channel per block, >= 1
  Pacing pacing = Pacing::kMax;
  Encoding encoding = Encoding::kFloat32;
  // Called once the session is open, before the first block (e.g. to print its id).
  std::function<void(const v1::SessionOpened&)> on_opened;
};

struct RemoteTrackResult {
  v1::SessionOpened opened;  // session id, token, effective config, backend
  StreamResult stream;       // estimates, rejections, gaps, latencies, final status
  double sample_rate_hz = 0.0;
};

// Opens a Track session with `config` sent field by field (wire::ConfigToProto, label
// attached, max_block_samples left 0 for the server's limit): what RunRemoteTrack and
// `simulate --server` send. Errors as TrackStream::Open.
StatusOr<std::unique_ptr<TrackStream>> OpenTrackSession(const std::shared_ptr<grpc::Channel>& channel,
                                                        const engine::AudioSessionConfig& config,
                                                        const std::string& label, const std::string& session_key);

// Errors before streaming (a file, the server refusing the config or unreachable: message
// prefixed by the gRPC code name) are returned as a Status. Once the session is open the
// result comes back even when the stream then fails: result.stream.status() says how it
// ended, and the estimates that arrived are in it and in the CSV. A CSV that cannot be
// written cancels the stream and is returned as the error. job.block_s is not used.
// Callbacks: on_warning before streaming; on_estimate and on_progress on the calling
// thread, as estimates arrive (progress counts samples read from the recording).
StatusOr<RemoteTrackResult> RunRemoteTrack(const std::shared_ptr<grpc::Channel>& channel, const io::TrackJob& job,
                                           const RemoteTrackOptions& options, const io::TrackCallbacks& callbacks = {},
                                           const StreamCallbacks& stream_callbacks = {});

}  // namespace localizer::client
