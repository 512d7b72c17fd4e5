#include "server/service/auth.h"

#include <openssl/crypto.h>
#include <openssl/sha.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <system_error>

namespace localizer::server {
namespace {

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r'; }

std::string_view Trim(std::string_view s) {
  while (!s.empty() && IsSpace(s.front())) s.remove_prefix(1);
  while (!s.empty() && IsSpace(s.back())) s.remove_suffix(1);
  return s;
}

// Splits on runs of spaces/tabs.
std::vector<std::string_view> Fields(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && IsSpace(line[i])) ++i;
    const size_t start = i;
    while (i < line.size() && !IsSpace(line[i])) ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

bool IsTokenChar(char c) { return c >= 0x21 && c <= 0x7e; }

}  // namespace

const char* RoleName(Role role) { return role == Role::kOperator ? "operator" : "client"; }

grpc::Status ToGrpcStatus(AuthDecision decision, const std::string& what) {
  switch (decision) {
    case AuthDecision::kAllowed:
      return grpc::Status::OK;
    case AuthDecision::kUnauthenticated:
      return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                          "missing or invalid bearer token (send metadata 'authorization: Bearer TOKEN')");
    case AuthDecision::kPermissionDenied:
      return grpc::Status(grpc::StatusCode::PERMISSION_DENIED,
                          "this token's role (client) may not call " + what + "; an operator token is needed");
  }
  return grpc::Status(grpc::StatusCode::INTERNAL, "unknown auth decision");
}

const char* RefusalReason(AuthDecision decision, std::string_view authorization) {
  switch (decision) {
    case AuthDecision::kAllowed:
      return "";
    case AuthDecision::kUnauthenticated:
      return authorization.empty() ? "missing" : "invalid";
    case AuthDecision::kPermissionDenied:
      return "forbidden";
  }
  return "invalid";
}

TokenAuthenticator::Digest TokenAuthenticator::Hash(std::string_view token) {
  Digest digest{};
  SHA256(reinterpret_cast<const unsigned char*>(token.data()), token.size(), digest.data());
  return digest;
}

StatusOr<std::unique_ptr<TokenAuthenticator>> TokenAuthenticator::Load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    return InvalidArgument("cannot read --auth-token-file \"" + path + "\": " + std::generic_category().message(errno));
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return InvalidArgument("cannot read --auth-token-file \"" + path + "\": read error");
  return Parse(text.str(), "--auth-token-file \"" + path + "\"");
}

StatusOr<std::unique_ptr<TokenAuthenticator>> TokenAuthenticator::Parse(std::string_view text,
                                                                        const std::string& source) {
  std::unique_ptr<TokenAuthenticator> auth(new TokenAuthenticator());
  std::set<Digest> seen;
  size_t line_number = 0;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find('\n', start), text.size());
    const std::string_view line = Trim(text.substr(start, end - start));
    start = end + 1;
    ++line_number;
    if (line.empty() || line.front() == '#') continue;
    const auto bad = [&](const std::string& why) {
      return InvalidArgument(source + " line " + std::to_string(line_number) + ": " + why);
    };
    const std::vector<std::string_view> fields = Fields(line);
    if (fields.size() != 2) {
      return bad("expected 'ROLE TOKEN' (ROLE client or operator), found " + std::to_string(fields.size()) +
                 " field(s)");
    }
    Role role;
    if (fields[0] == "client") {
      role = Role::kClient;
    } else if (fields[0] == "operator") {
      role = Role::kOperator;
    } else {
      return bad("role is not client or operator");
    }
    const std::string_view token = fields[1];
    if (token.size() < kMinTokenChars) {
      return bad("token has " + std::to_string(token.size()) + " characters; at least " +
                 std::to_string(kMinTokenChars) + " are needed (e.g. openssl rand -hex 32)");
    }
    if (token.size() > kMaxTokenChars) {
      return bad("token is longer than " + std::to_string(kMaxTokenChars) + " characters");
    }
    for (const char c : token) {
      if (!IsTokenChar(c)) return bad("token holds a character outside printable ASCII");
    }
    const Digest digest = Hash(token);
    if (!seen.insert(digest).second) return bad("token is listed twice");
    auth->entries_.push_back(Entry{role, digest});
  }
  if (auth->entries_.empty()) return InvalidArgument(source + " holds no token (lines 'ROLE TOKEN')");
  return auth;
}

AuthDecision TokenAuthenticator::Check(std::string_view authorization, Role required) const {
  constexpr std::string_view kScheme = "bearer ";
  if (authorization.size() <= kScheme.size()) return AuthDecision::kUnauthenticated;
  for (size_t i = 0; i < kScheme.size(); ++i) {
    const char c = authorization[i];
    const char lower = (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
    if (lower != kScheme[i]) return AuthDecision::kUnauthenticated;
  }
  const std::string_view token = Trim(authorization.substr(kScheme.size()));
  if (token.empty() || token.size() > kMaxTokenChars) return AuthDecision::kUnauthenticated;
  const Digest presented = Hash(token);
  // Every entry is compared; the match (at most one: digests are unique) is folded in
  // without branching on it.
  unsigned is_client = 0, is_operator = 0;
  for (const Entry& entry : entries_) {
    const unsigned match = CRYPTO_memcmp(presented.data(), entry.digest.data(), presented.size()) == 0 ? 1u : 0u;
    is_operator |= match & (entry.role == Role::kOperator ? 1u : 0u);
    is_client |= match & (entry.role == Role::kClient ? 1u : 0u);
  }
  if (is_operator != 0) return AuthDecision::kAllowed;
  if (is_client != 0) return required == Role::kClient ? AuthDecision::kAllowed : AuthDecision::kPermissionDenied;
  return AuthDecision::kUnauthenticated;
}

}  // namespace localizer::server
