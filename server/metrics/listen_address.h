// Parsing of the "host:port" listen addresses the HTTP side takes (--metrics-listen), shared
// by HttpExposer (civetweb) and TlsFront (its own socket), so both accept and refuse the same
// strings with the same messages.
#pragma once

#include <sys/socket.h>

#include <string>

#include "engine/core/status.h"

namespace localizer::server::metrics {

struct ListenAddress {
  std::string host;  // an IPv4 literal ("127.0.0.1"; "localhost" becomes that) or a bracketed
                     // IPv6 literal ("[::1]")
  int port = 0;      // 0..65535; 0: the kernel picks a free one
  bool ipv6() const { return !host.empty() && host.front() == '['; }
  // host:port again, normalised ("localhost:80" -> "127.0.0.1:80").
  std::string ToString() const { return host + ":" + std::to_string(port); }
};

// "host:port" -> ListenAddress. INVALID_ARGUMENT, quoting `listen` and giving an example,
// for a missing or out-of-range port, or a host that is not an IPv4 literal, a bracketed
// IPv6 literal or "localhost" (names are not resolved).
StatusOr<ListenAddress> ParseListenAddress(const std::string& listen);

// The socket address of `address` (host and port), written to *storage; returns its length,
// or 0 when the host does not parse (ParseListenAddress's output always does).
socklen_t ToSockaddr(const ListenAddress& address, sockaddr_storage* storage);

}  // namespace localizer::server::metrics
