#include "server/metrics/tls_front.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>
#include <openssl/x509.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <system_error>
#include <utility>
#include <vector>

#include "server/metrics/listen_address.h"

namespace localizer::server::metrics {
namespace {

constexpr int kListenBacklog = 64;
constexpr int kMaxConnections = 1024;

struct SslCtxFree {
  void operator()(SSL_CTX* ctx) const { SSL_CTX_free(ctx); }
};
struct SslFree {
  void operator()(SSL* ssl) const { SSL_free(ssl); }
};
struct BioFree {
  void operator()(BIO* bio) const { BIO_free(bio); }
};
struct X509Free {
  void operator()(X509* x509) const { X509_free(x509); }
};
struct PkeyFree {
  void operator()(EVP_PKEY* key) const { EVP_PKEY_free(key); }
};

// OpenSSL's first queued error as text ("error:0A00010B:SSL routines::wrong version number"),
// or `fallback`; clears the (per-thread) queue.
std::string OpensslError(const std::string& fallback = "") {
  const unsigned long code = ERR_peek_error();
  std::string text = fallback;
  if (code != 0) {
    char buffer[256];
    ERR_error_string_n(code, buffer, sizeof buffer);
    text = buffer;
  }
  ERR_clear_error();
  return text;
}

std::unique_ptr<BIO, BioFree> MemoryBio(const std::string& pem) {
  return std::unique_ptr<BIO, BioFree>(BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size())));
}

// Every certificate in `pem`, in order.
std::vector<std::unique_ptr<X509, X509Free>> Certificates(const std::string& pem) {
  std::vector<std::unique_ptr<X509, X509Free>> certificates;
  auto bio = MemoryBio(pem);
  if (bio == nullptr) return certificates;
  while (X509* certificate = PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr)) {
    certificates.emplace_back(certificate);
  }
  ERR_clear_error();  // the end of the text reads as a "no start line" error
  return certificates;
}

StatusOr<std::unique_ptr<SSL_CTX, SslCtxFree>> MakeContext(const TlsFrontOptions& options) {
  ERR_clear_error();
  std::unique_ptr<SSL_CTX, SslCtxFree> ctx(SSL_CTX_new(TLS_server_method()));
  if (ctx == nullptr) return Internal("cannot make an OpenSSL context: " + OpensslError());
  SSL_CTX_set_min_proto_version(ctx.get(), TLS1_2_VERSION);
  // No client-initiated renegotiation (TLS 1.2; a cheap way to make the server compute).
  SSL_CTX_set_options(ctx.get(), SSL_OP_NO_RENEGOTIATION | SSL_OP_CIPHER_SERVER_PREFERENCE);
  // Partial writes and a write buffer that may move: the relay retries from its own buffer.
  // Record buffers are released while a connection waits, so idle connections cost little.
  SSL_CTX_set_mode(ctx.get(),
                   SSL_MODE_ENABLE_PARTIAL_WRITE | SSL_MODE_ACCEPT_MOVING_WRITE_BUFFER | SSL_MODE_RELEASE_BUFFERS);
  // One request per connection: nothing to resume, so no session cache and no tickets.
  SSL_CTX_set_session_cache_mode(ctx.get(), SSL_SESS_CACHE_OFF);
  SSL_CTX_set_num_tickets(ctx.get(), 0);

  auto chain = Certificates(options.cert_chain_pem);
  if (chain.empty()) return InvalidArgument("TLS certificate chain holds no PEM certificate");
  if (SSL_CTX_use_certificate(ctx.get(), chain.front().get()) != 1) {
    return InvalidArgument("TLS certificate refused by OpenSSL: " + OpensslError());
  }
  for (size_t i = 1; i < chain.size(); ++i) {
    if (SSL_CTX_add1_chain_cert(ctx.get(), chain[i].get()) != 1) {
      return InvalidArgument("TLS intermediate certificate " + std::to_string(i) +
                             " refused by OpenSSL: " + OpensslError());
    }
  }
  auto key_bio = MemoryBio(options.key_pem);
  // An empty passphrase callback result: encrypted keys are refused, not prompted for.
  std::unique_ptr<EVP_PKEY, PkeyFree> key(
      key_bio == nullptr ? nullptr
                         : PEM_read_bio_PrivateKey(
                               key_bio.get(), nullptr, [](char*, int, int, void*) { return 0; }, nullptr));
  if (key == nullptr) {
    return InvalidArgument("TLS key holds no unencrypted PEM private key: " + OpensslError());
  }
  if (SSL_CTX_use_PrivateKey(ctx.get(), key.get()) != 1 || SSL_CTX_check_private_key(ctx.get()) != 1) {
    return InvalidArgument("TLS key is not the key of the certificate: " + OpensslError());
  }

  if (!options.client_ca_pem.empty()) {
    auto cas = Certificates(options.client_ca_pem);
    if (cas.empty()) return InvalidArgument("TLS client CA file holds no PEM certificate");
    X509_STORE* store = SSL_CTX_get_cert_store(ctx.get());
    for (const auto& ca : cas) {
      if (X509_STORE_add_cert(store, ca.get()) != 1 || SSL_CTX_add_client_CA(ctx.get(), ca.get()) != 1) {
        return InvalidArgument("TLS client CA certificate refused by OpenSSL: " + OpensslError());
      }
    }
    SSL_CTX_set_verify(ctx.get(), SSL_VERIFY_PEER | SSL_VERIFY_FAIL_IF_NO_PEER_CERT, nullptr);
  }
  ERR_clear_error();
  return ctx;
}

// "ip:port" or "[ip6]:port".
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

std::chrono::steady_clock::duration Seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

// What a poll on a connection's sockets says.
enum class Wait { kReady, kStop, kTimeout };

// Waits until `fd` has `events` (or an error), the stop eventfd is written, or `deadline`.
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

// Relays between the TLS connection and the backend socket until the backend has closed and
// everything it sent is delivered, either side fails, the stop eventfd is written, nothing
// moves for `idle`, or `deadline` passes.
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

}  // namespace

TlsFront::TlsFront(int backend_port, TlsFrontOptions options)
    : backend_port_(backend_port), options_(std::move(options)) {}

StatusOr<std::unique_ptr<TlsFront>> TlsFront::Start(const std::string& listen, int backend_port,
                                                    TlsFrontOptions options) {
  if (backend_port < 1 || backend_port > 65535) {
    return InvalidArgument("TlsFront backend port " + std::to_string(backend_port) + " is not in 1..65535");
  }
  if (options.max_connections < 1 || options.max_connections > kMaxConnections) {
    return InvalidArgument("TlsFront max_connections " + std::to_string(options.max_connections) + " is not in 1.." +
                           std::to_string(kMaxConnections));
  }
  if (!(options.handshake_timeout_s > 0.0 && options.handshake_timeout_s <= 3600.0)) {
    return InvalidArgument("TlsFront handshake_timeout_s must be in (0, 3600]");
  }
  if (!(options.idle_timeout_s > 0.0 && options.idle_timeout_s <= 86400.0)) {
    return InvalidArgument("TlsFront idle_timeout_s must be in (0, 86400]");
  }
  if (!(options.max_connection_s > 0.0 && options.max_connection_s <= 86400.0)) {
    return InvalidArgument("TlsFront max_connection_s must be in (0, 86400]");
  }
  if (options.buffer_bytes < 1024 || options.buffer_bytes > (1 << 20)) {
    return InvalidArgument("TlsFront buffer_bytes " + std::to_string(options.buffer_bytes) +
                           " is not in 1024..1048576");
  }
  if (!(options.report_interval_s >= 0.0 && options.report_interval_s <= 86400.0)) {
    return InvalidArgument("TlsFront report_interval_s must be in [0, 86400]");
  }
  StatusOr<ListenAddress> address = ParseListenAddress(listen);
  if (!address.ok()) return address.status();
  auto ctx = MakeContext(options);
  if (!ctx.ok()) return ctx.status();

  std::unique_ptr<TlsFront> front(new TlsFront(backend_port, std::move(options)));
  front->ctx_ = ctx->release();
  if (Family<Counter>* family = front->options_.handshake_failures) {
    for (int reason = 0; reason < kReasonCount; ++reason) {
      auto counter = family->WithLabels({kHandshakeFailureReasons[reason]});
      if (!counter.ok()) return counter.status();
      front->failure_counters_[reason] = *counter;
    }
  }

  sockaddr_storage storage{};
  const socklen_t length = ToSockaddr(*address, &storage);
  const auto unavailable = [&listen](const std::string& what) {
    return Unavailable("cannot serve HTTPS on \"" + listen + "\": " + what + ": " +
                       std::generic_category().message(errno));
  };
  front->listen_fd_ = socket(storage.ss_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (front->listen_fd_ < 0) return unavailable("socket");
  const int one = 1;
  // A restarted server may bind while its old connections sit in TIME_WAIT (a port with a
  // live listener still refuses it).
  setsockopt(front->listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (bind(front->listen_fd_, reinterpret_cast<const sockaddr*>(&storage), length) != 0) {
    return unavailable("cannot bind");
  }
  if (::listen(front->listen_fd_, kListenBacklog) != 0) return unavailable("cannot listen");
  sockaddr_storage bound{};
  socklen_t bound_length = sizeof bound;
  if (getsockname(front->listen_fd_, reinterpret_cast<sockaddr*>(&bound), &bound_length) != 0) {
    return unavailable("getsockname");
  }
  front->port_ = ntohs(bound.ss_family == AF_INET6 ? reinterpret_cast<const sockaddr_in6*>(&bound)->sin6_port
                                                   : reinterpret_cast<const sockaddr_in*>(&bound)->sin_port);
  front->stop_fd_ = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  front->notify_fd_ = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (front->stop_fd_ < 0 || front->notify_fd_ < 0) return unavailable("eventfd");
  try {
    front->accept_thread_ = std::thread(&TlsFront::AcceptLoop, front.get());
  } catch (const std::system_error& e) {
    return Unavailable("cannot serve HTTPS on \"" + listen + "\": no thread: " + e.what());
  }
  return front;
}

TlsFront::~TlsFront() {
  if (stop_fd_ >= 0) {
    const uint64_t one = 1;
    (void)!write(stop_fd_, &one, sizeof one);
  }
  if (accept_thread_.joinable()) accept_thread_.join();
  for (int fd : {listen_fd_, stop_fd_, notify_fd_}) {
    if (fd >= 0) close(fd);
  }
  SSL_CTX_free(ctx_);
}

void TlsFront::Notify() const {
  const uint64_t one = 1;
  (void)!write(notify_fd_, &one, sizeof one);
}

void TlsFront::AcceptLoop() {
  for (;;) {
    ReapFinished();
    int timeout_ms = MillisecondsToNextReport();
    // Below the cap, accept. At the cap the listener is polled only when an eviction could make
    // room; otherwise new connections wait in the kernel's backlog.
    bool poll_listener = true;
    Connection* candidate = nullptr;
    if (connections_.size() >= static_cast<size_t>(options_.max_connections)) {
      int ripe_in_ms = -1;
      candidate = EvictionCandidate(&ripe_in_ms);
      poll_listener = candidate != nullptr;
      if (candidate == nullptr && ripe_in_ms >= 0) {
        timeout_ms = timeout_ms < 0 ? ripe_in_ms : std::min(timeout_ms, ripe_in_ms);
      }
    }
    pollfd fds[3] = {{stop_fd_, POLLIN, 0}, {notify_fd_, POLLIN, 0}, {poll_listener ? listen_fd_ : -1, POLLIN, 0}};
    if (poll(fds, 3, timeout_ms) < 0) {
      // EINTR; or ENOMEM, which may pass: the front must not stop serving for it.
      if (errno != EINTR) std::this_thread::sleep_for(std::chrono::milliseconds(10));
      continue;
    }
    if (fds[0].revents != 0) break;
    if (fds[1].revents != 0) {
      uint64_t count = 0;
      (void)!read(notify_fd_, &count, sizeof count);
    }
    ReportFailures(false);
    if (fds[2].revents != 0) {
      if (candidate != nullptr) {
        Evict(candidate);  // its thread ends within milliseconds and notifies; then we accept
      } else {
        AcceptOne();
      }
    }
  }
  // Every connection thread polls stop_fd_ too, so these joins take milliseconds.
  for (auto& connection : connections_) connection->thread.join();
  connections_.clear();
  ReportFailures(true);
}

TlsFront::Connection* TlsFront::EvictionCandidate(int* ripe_in_ms) {
  *ripe_in_ms = -1;
  Connection* oldest = nullptr;
  for (auto& connection : connections_) {  // in the order they were accepted
    MutexLock lock(&connection->mutex);
    if (connection->evicted) return nullptr;  // one at a time: wait until it has made room
    if (connection->handshaking && oldest == nullptr) oldest = connection.get();
  }
  if (oldest == nullptr) return nullptr;
  const auto ripe_at = oldest->accepted_at + Seconds(options_.handshake_timeout_s / 4);
  if (Clock::now() >= ripe_at) return oldest;
  *ripe_in_ms = std::max(1, MillisecondsUntil(ripe_at));
  return nullptr;
}

void TlsFront::Evict(Connection* connection) {
  MutexLock lock(&connection->mutex);
  if (!connection->handshaking || connection->fd < 0) return;  // finished meanwhile
  connection->evicted = true;
  shutdown(connection->fd, SHUT_RDWR);  // wakes its poll; its SSL_accept then fails
}

void TlsFront::AcceptOne() {
  sockaddr_storage peer{};
  socklen_t peer_length = sizeof peer;
  const int fd = accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &peer_length, SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd < 0) {
    // Out of descriptors: the connection stays in the backlog, and the listener stays readable;
    // a short pause keeps this loop from spinning until one is freed.
    if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return;  // EAGAIN (the client gave up), ECONNABORTED, EINTR: nothing to do
  }
  auto connection = std::make_unique<Connection>();
  {
    MutexLock lock(&connection->mutex);
    connection->fd = fd;
  }
  connection->peer = PeerString(peer);
  connection->accepted_at = Clock::now();
  try {
    connection->thread = std::thread(&TlsFront::Serve, this, connection.get());
  } catch (const std::system_error&) {
    close(fd);  // no thread to spare: this client is turned away
    return;
  }
  connections_.push_back(std::move(connection));
}

void TlsFront::ReapFinished() {
  for (auto it = connections_.begin(); it != connections_.end();) {
    if ((*it)->done.load()) {
      (*it)->thread.join();
      it = connections_.erase(it);
    } else {
      ++it;
    }
  }
}

void TlsFront::Serve(Connection* connection) {
  // OpenSSL writes to the socket with write(2): a client that has gone raises SIGPIPE, which
  // would end the process. civetweb's mg_start ignores SIGPIPE process-wide (so in the server
  // this is already so), but the front does not rely on it: blocked on this thread, the signal
  // stays pending here and is dropped when the thread ends; the write fails with EPIPE.
  sigset_t pipe_signal;
  sigemptyset(&pipe_signal);
  sigaddset(&pipe_signal, SIGPIPE);
  pthread_sigmask(SIG_BLOCK, &pipe_signal, nullptr);

  int client_fd = -1;
  {
    MutexLock lock(&connection->mutex);
    client_fd = connection->fd;
  }
  std::unique_ptr<SSL, SslFree> ssl(SSL_new(ctx_));
  if (ssl != nullptr && SSL_set_fd(ssl.get(), client_fd) == 1) {
    const Handshake handshake = HandshakeWith(ssl.get(), client_fd);
    bool evicted = false;
    {
      MutexLock lock(&connection->mutex);
      connection->handshaking = false;
      evicted = connection->evicted;
    }
    if (evicted) {
      RecordFailure(kEvicted, "", connection->peer);
    } else if (handshake.failure != kReasonCount) {
      RecordFailure(handshake.failure, handshake.detail, connection->peer);
    } else if (handshake.done) {
      RelayToBackend(ssl.get(), client_fd, connection->accepted_at + Seconds(options_.max_connection_s));
    }
  }
  ssl.reset();
  ERR_clear_error();
  {
    MutexLock lock(&connection->mutex);
    close(connection->fd);
    connection->fd = -1;
  }
  connection->done.store(true);
  Notify();
}

TlsFront::Handshake TlsFront::HandshakeWith(SSL* ssl, int client_fd) const {
  Handshake handshake;
  const auto deadline = Clock::now() + Seconds(options_.handshake_timeout_s);
  for (;;) {
    ERR_clear_error();
    const int result = SSL_accept(ssl);
    if (result == 1) {
      handshake.done = true;
      return handshake;
    }
    const int error = SSL_get_error(ssl, result);
    if (error == SSL_ERROR_WANT_READ || error == SSL_ERROR_WANT_WRITE) {
      const Wait wait = WaitFor(client_fd, error == SSL_ERROR_WANT_READ ? POLLIN : POLLOUT, stop_fd_, deadline);
      if (wait == Wait::kStop) return handshake;  // shutting down: not the client's failure
      if (wait == Wait::kTimeout) {
        handshake.failure = kTimeout;
        return handshake;
      }
      continue;
    }
    const unsigned long code = ERR_peek_error();
    const bool eof = (code == 0 && (error == SSL_ERROR_SYSCALL || error == SSL_ERROR_ZERO_RETURN)) ||
                     (ERR_GET_LIB(code) == ERR_LIB_SSL && ERR_GET_REASON(code) == SSL_R_UNEXPECTED_EOF_WHILE_READING);
    const long verify = SSL_get_verify_result(ssl);
    if (eof) {
      handshake.failure = kClosed;  // e.g. a TCP check that connects and closes
      ERR_clear_error();
    } else if (verify != X509_V_OK) {
      handshake.failure = kCertificate;
      handshake.detail = X509_verify_cert_error_string(verify);
      ERR_clear_error();
    } else if (ERR_GET_LIB(code) == ERR_LIB_SSL && ERR_GET_REASON(code) == SSL_R_PEER_DID_NOT_RETURN_A_CERTIFICATE) {
      handshake.failure = kCertificate;
      handshake.detail = OpensslError();
    } else {
      handshake.failure = kProtocol;
      handshake.detail = OpensslError("handshake failed");
    }
    return handshake;
  }
}

void TlsFront::RelayToBackend(SSL* ssl, int client_fd, Clock::time_point deadline) const {
  // Only now is the backend involved: a connection that fails the handshake never reaches it.
  const int backend_fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (backend_fd < 0) return;
  sockaddr_in backend{};
  backend.sin_family = AF_INET;
  backend.sin_port = htons(static_cast<uint16_t>(backend_port_));
  backend.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bool connected = connect(backend_fd, reinterpret_cast<const sockaddr*>(&backend), sizeof backend) == 0;
  if (!connected && errno == EINPROGRESS &&
      WaitFor(backend_fd, POLLOUT, stop_fd_, Clock::now() + Seconds(options_.idle_timeout_s)) == Wait::kReady) {
    int error = 0;
    socklen_t error_length = sizeof error;
    connected = getsockopt(backend_fd, SOL_SOCKET, SO_ERROR, &error, &error_length) == 0 && error == 0;
  }
  if (connected) {
    Relay(ssl, client_fd, backend_fd, stop_fd_, options_.buffer_bytes, Seconds(options_.idle_timeout_s), deadline);
  }
  close(backend_fd);
}

void TlsFront::RecordFailure(FailureReason reason, std::string detail, const std::string& peer) {
  total_failures_.fetch_add(1);
  if (Counter* counter = failure_counters_[reason]) counter->Increment();
  bool first_pending = false;
  {
    MutexLock lock(&failures_mutex_);
    first_pending = pending_.failures == 0;
    ++pending_.failures;
    pending_.last_reason = kHandshakeFailureReasons[reason];
    pending_.last_detail = std::move(detail);
    pending_.last_peer = peer;
  }
  if (first_pending && options_.report_failures) Notify();  // the accept loop reports it when due
}

int TlsFront::MillisecondsToNextReport() const {
  MutexLock lock(&failures_mutex_);
  if (pending_.failures == 0 || !options_.report_failures) return -1;
  if (next_report_at_ == Clock::time_point::min()) return 0;
  return MillisecondsUntil(next_report_at_);
}

void TlsFront::ReportFailures(bool force) {
  if (!options_.report_failures) return;
  HandshakeFailureReport report;
  {
    MutexLock lock(&failures_mutex_);
    const auto now = Clock::now();
    if (pending_.failures == 0 || (!force && now < next_report_at_)) return;
    report = std::move(pending_);
    pending_ = HandshakeFailureReport();
    next_report_at_ = now + Seconds(options_.report_interval_s);
  }
  options_.report_failures(report);
}

}  // namespace localizer::server::metrics
