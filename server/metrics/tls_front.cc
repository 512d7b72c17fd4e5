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
#include "server/metrics/tls_openssl.h"
#include "server/metrics/tls_relay.h"

namespace localizer::server::metrics {
namespace {

constexpr int kListenBacklog = 64;
constexpr int kMaxConnections = 1024;

std::chrono::steady_clock::duration Seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
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
  auto ctx = MakeTlsServerContext(options);
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
