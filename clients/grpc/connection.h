// Channels to a localizer server, and the conventions every client call shares.
//
// Connect(target) makes a plaintext channel; Connect(target, ConnectOptions) adds TLS (the
// server verified against a CA), a client certificate (mutual TLS) and a bearer token sent
// on every call (docs/SECURITY.md). Messages up to 64 MiB pass either way,
// enough for a block of 2^20 samples on 16 float32 channels. A grpc::Channel is thread-safe
// and cheap to share; a failed connection is retried by gRPC in the background.
#pragma once

#include <grpcpp/channel.h>
#include <grpcpp/client_context.h>

#include <memory>
#include <string>

#include "clients/grpc/connect_options.h"
#include "engine/core/status.h"

namespace localizer::client {

// Largest message sent or received on a channel from Connect, bytes.
inline constexpr int kMaxMessageBytes = 64 << 20;

// Metadata key a proxy routes a session by (see the proto's header comment).
inline constexpr const char* kSessionKeyMetadata = "x-localizer-session-key";

// A channel to "HOST:PORT" (any gRPC target: "dns:///host:port", "unix:/path", ...). Never
// fails here: connection errors surface on the first call as UNAVAILABLE.
std::shared_ptr<grpc::Channel> Connect(const std::string& target);


// A channel with `options`' credentials; the token goes out as "authorization: Bearer
// TOKEN" on every call (also over plaintext, for a TLS-terminating proxy in front: keep such
// a leg on a trusted network). INVALID_ARGUMENT naming the flag and path when a file cannot
// be read, is not PEM or holds no token, or when only one of tls_cert / tls_key is given.
StatusOr<std::shared_ptr<grpc::Channel>> Connect(const std::string& target, const ConnectOptions& options);

// The token in an --auth-token-file (see ConnectOptions), or INVALID_ARGUMENT.
StatusOr<std::string> ReadTokenFile(const std::string& path);

// Blocks until the channel is READY. UNAVAILABLE ("UNAVAILABLE: not connected to ... after
// 2 s (state TRANSIENT_FAILURE)") when `timeout_s` passes first; INVALID_ARGUMENT for a
// negative or non-finite timeout.
Status WaitConnected(const std::shared_ptr<grpc::Channel>& channel, double timeout_s);

// Puts `session_key` on `context` as kSessionKeyMetadata (nothing for an empty key).
void SetSessionKey(grpc::ClientContext* context, const std::string& session_key);

// How a client reads the end of a call that went through a proxy. When the server instance
// behind an HTTP/2 proxy (deploy/nginx) dies mid-stream, the proxy cannot send gRPC trailers
// for it; it resets the client's stream (RST_STREAM INTERNAL_ERROR), which gRPC reports as
// INTERNAL "Received RST_STREAM with error code 2". Our server never ends a call that way (it
// always sends a status), so that reset means "the instance is gone": returned here as
// UNAVAILABLE, the code a direct connection reports for the same loss, with the original
// details kept. Every other status is returned unchanged.
grpc::Status FromProxyReset(const grpc::Status& status);

// A fresh random key ("cli-" and 16 hex digits) for a client that has no stable name.
std::string RandomSessionKey();

}  // namespace localizer::client
