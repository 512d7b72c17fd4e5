// Per-call bearer-token authentication and the two roles (client, operator).
//
// Token file (--auth-token-file), UTF-8 text, one token per line:
//
//   # who may do what; blank lines and lines starting with '#' are ignored
//   client    4f0c9a1e7b2d4c88a6d1e0f3b5a79c21
//   operator  b7e1d2c3a4f5061728394a5b6c7d8e9f
//
// Each line is a role (`client` or `operator`), whitespace (spaces or tabs), then the token:
// 16..4096 printable ASCII characters without whitespace (0x21..0x7e). A line with another
// role, a short or bad token, more than two fields, or a token listed twice is refused when the
// file is loaded, with the file name and line number (the token itself is never echoed).
// Generate tokens with e.g. `openssl rand -hex 32`.
//
// What each role may call:
//
//   method                 client   operator
//   Track, Locate            yes      yes
//   ListSessions             no       yes
//   CloseSession             no       yes
//   HTTP /sessions, /        no       yes      (see server.cc; /metrics stays open)
//
// Clients send the gRPC metadata `authorization: Bearer <token>` (HTTP: the header
// `Authorization: Bearer <token>`; the scheme is case-insensitive). Check() answers:
//   kAllowed            a known token whose role may do the call;
//   kUnauthenticated    no authorization value, not "Bearer <token>", or an unknown token
//                       (gRPC UNAUTHENTICATED, HTTP 401; no message contains what was sent);
//   kPermissionDenied   a known client token on an operator-only call (gRPC
//                       PERMISSION_DENIED, HTTP 403).
//
// Tokens are kept only as SHA-256 digests. A presented token is hashed and compared with
// every known digest by CRYPTO_memcmp, without stopping at a match, so the time taken
// depends neither on how much of a token matched nor on which entry did (only on the
// number of entries and the presented length, which hashing hides from the comparison).
//
// Thread-safety: immutable after Load; Check may run on any thread concurrently.
#pragma once

#include <grpcpp/support/status.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/status.h"

namespace localizer::server {

enum class Role { kClient, kOperator };

const char* RoleName(Role role);

// The outcome of a check. (engine::StatusCode has no UNAUTHENTICATED: this stays in server/.)
enum class AuthDecision { kAllowed, kUnauthenticated, kPermissionDenied };

// OK, UNAUTHENTICATED ("missing or invalid bearer token") or PERMISSION_DENIED ("this token's
// role (client) may not call <what>; an operator token is needed"), for gRPC.
grpc::Status ToGrpcStatus(AuthDecision decision, const std::string& what);

// Why a request was refused, the `reason` of localizer_auth_refusals_total: "missing" (no
// credentials: `authorization` is empty), "invalid" (credentials sent, but not "Bearer TOKEN"
// or a token that is not in the file), "forbidden" (a known token whose role may not make the
// call). "" for kAllowed.
const char* RefusalReason(AuthDecision decision, std::string_view authorization);

class TokenAuthenticator final {
 public:
  static constexpr size_t kMinTokenChars = 16;
  static constexpr size_t kMaxTokenChars = 4096;

  // Reads `path`. INVALID_ARGUMENT naming the flag (--auth-token-file), the path and, for a
  // bad line, its number; an unreadable file or one without any token is refused too.
  static StatusOr<std::unique_ptr<TokenAuthenticator>> Load(const std::string& path);
  // The same from text; `source` names it in errors.
  static StatusOr<std::unique_ptr<TokenAuthenticator>> Parse(std::string_view text, const std::string& source);

  // `authorization` is the value of the authorization metadata/header ("" when absent).
  // `required` is the least role the call needs (kClient: any known token).
  AuthDecision Check(std::string_view authorization, Role required) const;

  size_t token_count() const { return entries_.size(); }

 private:
  using Digest = std::array<uint8_t, 32>;
  struct Entry {
    Role role;
    Digest digest;
  };
  TokenAuthenticator() = default;
  static Digest Hash(std::string_view token);

  std::vector<Entry> entries_;
};

// The gRPC metadata key (lower case, as gRPC delivers it) and HTTP header of the token.
inline constexpr const char* kAuthorizationMetadata = "authorization";

}  // namespace localizer::server
