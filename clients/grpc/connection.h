// Channels to a localizer server, and the conventions every client call shares.
//
// Channels are plaintext (insecure credentials): the service runs inside a trusted network
// or behind a TLS-terminating proxy (deploy/nginx). Messages up to 64 MiB pass either way,
// enough for a block of 2^20 samples on 16 float32 channels. A grpc::Channel is thread-safe
// and cheap to share; a failed connection is retried by gRPC in the background.
#pragma once

#include <grpcpp/channel.h>
#include <grpcpp/client_context.h>

#include <memory>
#include <string>

#include "engine/core/status.h"

namespace localizer::client {

// Largest message sent or received on a channel from Connect, bytes.
inline constexpr int kMaxMessageBytes = 64 << 20;

// Metadata key a proxy routes a session by (see the proto's header comment).
inline constexpr const char* kSessionKeyMetadata = "x-localizer-session-key";

// A channel to "HOST:PORT" (any gRPC target: "dns:///host:port", "unix:/path", ...). Never
// fails here: connection errors surface on the first call as UNAVAILABLE.
std::shared_ptr<grpc::Channel> Connect(const std::string& target);

// Blocks until the channel is READY. UNAVAILABLE ("UNAVAILABLE: not connected to ... after
// 2 s (state TRANSIENT_FAILURE)") when `timeout_s` passes first; INVALID_ARGUMENT for a
// negative or non-finite timeout.
Status WaitConnected(const std::shared_ptr<grpc::Channel>& channel, double timeout_s);

// Puts `session_key` on `context` as kSessionKeyMetadata (nothing for an empty key).
void SetSessionKey(grpc::ClientContext* context, const std::string& session_key);

// A fresh random key ("cli-" and 16 hex digits) for a client that has no stable name.
std::string RandomSessionKey();

}  // namespace localizer::client
