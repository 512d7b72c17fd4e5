#include "server/metrics/listen_address.h"

#include <arpa/inet.h>
#include <netinet/in.h>

#include <cstring>

namespace localizer::server::metrics {

StatusOr<ListenAddress> ParseListenAddress(const std::string& listen) {
  const auto bad = [&listen](const std::string& why) {
    return InvalidArgument("listen address \"" + listen + "\" " + why +
                           " (expected host:port, e.g. 127.0.0.1:9100 or [::1]:0)");
  };
  const size_t colon = listen.rfind(':');
  if (colon == std::string::npos) return bad("has no port");
  ListenAddress address;
  address.host = listen.substr(0, colon);
  const std::string port = listen.substr(colon + 1);
  if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos ||
      std::stoi(port) > 65535) {
    return bad("has no port number in 0..65535");
  }
  address.port = std::stoi(port);
  if (address.host == "localhost") address.host = "127.0.0.1";
  unsigned char bytes[16];
  const std::string& host = address.host;
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') {
    if (inet_pton(AF_INET6, host.substr(1, host.size() - 2).c_str(), bytes) != 1) return bad("has a bad IPv6 host");
  } else if (inet_pton(AF_INET, host.c_str(), bytes) != 1) {
    return bad("has a host that is not an IPv4 literal, [IPv6] literal or localhost");
  }
  return address;
}

socklen_t ToSockaddr(const ListenAddress& address, sockaddr_storage* storage) {
  std::memset(storage, 0, sizeof *storage);
  const uint16_t port = htons(static_cast<uint16_t>(address.port));
  if (address.ipv6()) {
    if (address.host.size() < 3 || address.host.back() != ']') return 0;
    auto* v6 = reinterpret_cast<sockaddr_in6*>(storage);
    v6->sin6_family = AF_INET6;
    v6->sin6_port = port;
    if (inet_pton(AF_INET6, address.host.substr(1, address.host.size() - 2).c_str(), &v6->sin6_addr) != 1) return 0;
    return sizeof *v6;
  }
  auto* v4 = reinterpret_cast<sockaddr_in*>(storage);
  v4->sin_family = AF_INET;
  v4->sin_port = port;
  if (inet_pton(AF_INET, address.host.c_str(), &v4->sin_addr) != 1) return 0;
  return sizeof *v4;
}

}  // namespace localizer::server::metrics
