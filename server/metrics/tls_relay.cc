#include "server/metrics/tls_relay.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <openssl/err.h>
#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <vector>

namespace localizer::server::metrics {
namespace {

// A fixed-size byte queue that refills only once drained, so the bytes of an SSL_write that
// must be retried stay where they were.
class RelayBuffer {
 public:
  explicit RelayBuffer(int bytes) : data_(static_cast<size_t>(bytes)) {}
  char* head() { return data_.data() + begin_; }
  char* tail() { return data_.data() + end_; }
  size_t size() const { return end_ - begin_; }
  size_t space() const { return data_.size() - end_; }
  void Added(size_t n) { end_ += n; }
  void Consumed(size_t n) {
    begin_ += n;
    if (begin_ == end_) begin_ = end_ = 0;
  }

 private:
  std::vector<char> data_;
  size_t begin_ = 0;
  size_t end_ = 0;
};

}  // namespace

std::string PeerString(const sockaddr_storage& peer) {
  char host[INET6_ADDRSTRLEN] = "?";
  int port = 0;
  const bool v6 = peer.ss_family == AF_INET6;
  if (v6) {
    const auto* address = reinterpret_cast<const sockaddr_in6*>(&peer);
    inet_ntop(AF_INET6, &address->sin6_addr, host, sizeof host);
    port = ntohs(address->sin6_port);
  } else if (peer.ss_family == AF_INET) {
    const auto* address = reinterpret_cast<const sockaddr_in*>(&peer);
    inet_ntop(AF_INET, &address->sin_addr, host, sizeof host);
    port = ntohs(address->sin_port);
  }
  std::string text;
  text.reserve(INET6_ADDRSTRLEN + 8);
  if (v6) text += '[';
  text += host;
  if (v6) text += ']';
  text += ':';
  text += std::to_string(port);
  return text;
}

int MillisecondsUntil(std::chrono::steady_clock::time_point deadline) {
  const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
  return static_cast<int>(std::clamp<int64_t>(left.count(), 0, 1 << 30));
}

Wait WaitFor(int fd, short events, int stop_fd, std::chrono::steady_clock::time_point deadline) {
  for (;;) {
    pollfd fds[2] = {{stop_fd, POLLIN, 0}, {fd, events, 0}};
    const int n = poll(fds, 2, MillisecondsUntil(deadline));
    if (n < 0 && errno == EINTR) continue;
    if (fds[0].revents != 0) return Wait::kStop;
    if (n > 0) return Wait::kReady;
    if (n == 0) return Wait::kTimeout;
    return Wait::kReady;  // a poll error: let the caller's next call see it
  }
}

void Relay(SSL* ssl, int client_fd, int backend_fd, int stop_fd, int buffer_bytes,
           std::chrono::steady_clock::duration idle, std::chrono::steady_clock::time_point deadline) {
  RelayBuffer up(buffer_bytes);    // client -> backend (decrypted)
  RelayBuffer down(buffer_bytes);  // backend -> client (to encrypt)
  bool client_done = false;        // close_notify received: the client sends nothing more
  // False once the backend takes no more bytes: it stopped reading (it answers and closes,
  // e.g. after a timeout or an error status), or the client's close was passed on. The client
  // is then no longer read; what the backend still sends is delivered.
  bool backend_writable = true;
  bool backend_done = false;  // the backend closed (its response is complete)
  int retry_write_bytes = 0;  // an SSL_write that must be repeated with the same length
  auto last_progress = std::chrono::steady_clock::now();
  for (;;) {
    bool progress = false;
    short client_events = 0;
    short backend_events = 0;
    if (!client_done && backend_writable && up.space() > 0) {
      ERR_clear_error();
      const int n = SSL_read(ssl, up.tail(), static_cast<int>(up.space()));
      if (n > 0) {
        up.Added(static_cast<size_t>(n));
        progress = true;
      } else {
        switch (SSL_get_error(ssl, n)) {
          case SSL_ERROR_WANT_READ:
            client_events |= POLLIN;
            break;
          case SSL_ERROR_WANT_WRITE:
            client_events |= POLLOUT;
            break;
          case SSL_ERROR_ZERO_RETURN:
            client_done = true;
            progress = true;
            break;
          default:  // reset, EOF without close_notify, a protocol error: nothing more to do
            ERR_clear_error();
            return;
        }
      }
    }
    if (backend_writable && up.size() > 0) {
      const ssize_t n = send(backend_fd, up.head(), up.size(), MSG_NOSIGNAL);
      if (n > 0) {
        up.Consumed(static_cast<size_t>(n));
        progress = true;
      } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
        backend_events |= POLLOUT;
      } else if (n < 0 && errno == EINTR) {
        progress = true;
      } else {
        backend_writable = false;  // closed or reset: drop what is left, deliver its answer
        up.Consumed(up.size());
        progress = true;
      }
    } else if (client_done && backend_writable) {
      // The client half-closed: pass it on (civetweb answers a complete request, then closes).
      shutdown(backend_fd, SHUT_WR);
      backend_writable = false;
    }
    if (!backend_done && down.space() > 0) {
      const ssize_t n = recv(backend_fd, down.tail(), down.space(), 0);
      if (n > 0) {
        down.Added(static_cast<size_t>(n));
        progress = true;
      } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
        backend_events |= POLLIN;
      } else if (n < 0 && errno == EINTR) {
        progress = true;
      } else {
        backend_done = true;  // closed (or reset): deliver what it sent, then end
        progress = true;
      }
    }
    if (down.size() > 0) {
      const int length = retry_write_bytes > 0 ? retry_write_bytes : static_cast<int>(down.size());
      ERR_clear_error();
      const int n = SSL_write(ssl, down.head(), length);
      if (n > 0) {
        down.Consumed(static_cast<size_t>(n));
        retry_write_bytes = 0;
        progress = true;
      } else {
        switch (SSL_get_error(ssl, n)) {
          case SSL_ERROR_WANT_WRITE:
            retry_write_bytes = length;
            client_events |= POLLOUT;
            break;
          case SSL_ERROR_WANT_READ:
            retry_write_bytes = length;
            client_events |= POLLIN;
            break;
          default:
            ERR_clear_error();
            return;  // the client is gone
        }
      }
    }
    if (backend_done && down.size() == 0) {
      ERR_clear_error();
      (void)SSL_shutdown(ssl);  // our close_notify, best effort: the response is complete
      ERR_clear_error();
      return;
    }
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return;
    if (progress) {
      last_progress = now;
      continue;
    }
    if (now - last_progress >= idle) return;
    // Only the sockets something waits on are polled: a hung-up socket that nothing waits on
    // would otherwise wake the poll at once, over and over.
    pollfd fds[3] = {{stop_fd, POLLIN, 0},
                     {client_events != 0 ? client_fd : -1, client_events, 0},
                     {backend_events != 0 ? backend_fd : -1, backend_events, 0}};
    const int n = poll(fds, 3, MillisecondsUntil(std::min(last_progress + idle, deadline)));
    if (n < 0 && errno != EINTR) return;
    if (fds[0].revents != 0) return;
  }
}

}  // namespace localizer::server::metrics
