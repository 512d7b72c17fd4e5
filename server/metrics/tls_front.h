// TlsFront: HTTPS (and mutual TLS) in front of HttpExposer, with OpenSSL 3 directly.
//
// Debian 12's civetweb cannot do TLS against OpenSSL 3 (docs/SECURITY.md, "HTTP and TLS"),
// so the server serves its HTTP pages over HTTPS this way instead:
//
//   client --TLS--> TlsFront (public address) --plain TCP--> civetweb on 127.0.0.1:backend_port
//
// TlsFront listens on the public address with a plain TCP socket, accepts connections,
// performs the TLS handshake (TLS 1.2 or 1.3; the server certificate chain and key; with
// client CAs, a client certificate is required and verified: mutual TLS), then opens a
// loopback connection to the backend and relays bytes both ways until the backend closes
// (civetweb closes after each response: no keep-alive) or the client goes away. The backend
// never sees a connection that has not completed the handshake.
//
// Bounds (TlsFrontOptions, defaults in brackets):
//   max_connections [16]      connections served at once (handshaking or relaying). Beyond it
//                             new connections are not accepted at once: they wait in the
//                             kernel's listen backlog (64), and while one waits, the oldest
//                             connection still in its handshake is closed to make room once
//                             it is older than handshake_timeout_s / 4 (0.5 s; reason
//                             "evicted"). So clients idle before the handshake delay a scrape
//                             by about 0.5 s per 16 of them ahead of it, instead of 2 s; a full
//                             backlog beyond that makes the kernel drop SYNs (clients retry).
//                             Connections past the handshake are never evicted (civetweb's 2 s
//                             request timeout and idle_timeout_s bound them).
//   handshake_timeout_s [2]   a connection that has not completed the handshake by then is
//                             closed (as civetweb's own 2 s request timeout does for a
//                             request); counted as a handshake failure, reason "timeout".
//   idle_timeout_s [10]       a relay with no byte moved in either direction for this long is
//                             closed (e.g. a client that stops reading its response). After the
//                             handshake civetweb's 2 s request timeout applies too.
//   max_connection_s [60]     a connection is closed this long after it was accepted, whatever
//                             it is doing (a client trickling its request a byte at a time keeps
//                             neither the idle timeout nor civetweb's from firing).
//   buffer_bytes [16384]      per direction per connection; reading from a side stops while its
//                             buffer is full (backpressure), so memory per connection is
//                             2 * buffer_bytes plus OpenSSL's record buffers (released while idle).
// One thread per connection (at most max_connections) plus one accept thread.
//
// Handshake failures (plain HTTP or garbage sent to the port, a client that does not trust
// the server's CA, a missing or unverifiable client certificate, a timeout) close the
// connection without an HTTP answer and never reach the backend. They are counted, by reason
// (timeout | closed | certificate | protocol | evicted), in the optional counter family, and
// reported to the optional callback at most once per report_interval_s (the first one at once,
// later ones summed), so a flood of bad connections cannot flood the log.
//
// Lifetime: Start binds and starts the accept thread; the destructor wakes every thread (an
// eventfd each of them polls), joins them (connections in flight are closed; it takes
// milliseconds), makes a last report of failures not yet reported and closes the socket. The
// backend (HttpExposer) and the counter family must outlive the TlsFront; destroy the
// TlsFront first.
//
// Thread-safety: port() and handshake_failures() may be called from any thread. The callback
// runs on the accept thread, never concurrently with itself; it must not block for long (new
// connections wait meanwhile).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <string>
#include <thread>

#include "engine/core/status.h"
#include "server/metrics/family.h"
#include "server/metrics/metric_types.h"
#include "server/sync/mutex.h"

struct ssl_ctx_st;  // OpenSSL's SSL_CTX
struct ssl_st;      // OpenSSL's SSL

namespace localizer::server::metrics {

// The `reason` label values of handshake failures, in FailureReason order.
inline constexpr const char* kHandshakeFailureReasons[] = {"timeout", "closed", "certificate", "protocol", "evicted"};

// Handshake failures summed since the previous report.
struct HandshakeFailureReport {
  int64_t failures = 0;     // >= 1
  std::string last_reason;  // timeout | closed | certificate | protocol | evicted
  std::string last_detail;  // OpenSSL's reason for the last one ("" for timeout and closed)
  std::string last_peer;    // the last one's client address, "ip:port"
};

struct TlsFrontOptions {
  // PEM texts (tls_credentials.h reads and checks the files, naming the flags).
  std::string cert_chain_pem;  // the server certificate, then any intermediates
  std::string key_pem;         // its private key, unencrypted
  std::string client_ca_pem;   // "": no client certificate asked; else one is required and
                               // must chain to one of these certificates (mutual TLS)

  int max_connections = 16;          // 1..1024
  double handshake_timeout_s = 2.0;  // (0, 3600]
  double idle_timeout_s = 10.0;      // (0, 86400]
  double max_connection_s = 60.0;    // (0, 86400]
  int buffer_bytes = 16384;          // 1024..1 MiB, per direction per connection

  // A counter family with the one label "reason" (or null): each failure increments its
  // series; all five series are created at Start, so they are exported at 0.
  Family<Counter>* handshake_failures = nullptr;
  std::function<void(const HandshakeFailureReport&)> report_failures;  // may be empty
  double report_interval_s = 60.0;                                     // >= 0
};

class TlsFront final {
 public:
  // Listens on `listen` ("host:port" as HttpExposer takes it: an IPv4 literal, a bracketed
  // IPv6 literal or localhost; port 0 picks a free one) and relays to 127.0.0.1:backend_port.
  // Errors: INVALID_ARGUMENT for a malformed address, a backend port outside 1..65535, limits
  // out of range, or PEM that OpenSSL cannot use (no certificate, no key, a key that is not
  // the certificate's, no CA certificate in client_ca_pem), with OpenSSL's reason;
  // UNAVAILABLE when the address cannot be bound (in use, not local), naming it.
  static StatusOr<std::unique_ptr<TlsFront>> Start(const std::string& listen, int backend_port,
                                                   TlsFrontOptions options);

  ~TlsFront();
  TlsFront(const TlsFront&) = delete;
  TlsFront& operator=(const TlsFront&) = delete;

  // The TCP port the front listens on (the chosen one when Start was given port 0).
  int port() const { return port_; }
  // Handshake failures since Start, every reason.
  int64_t handshake_failures() const { return total_failures_.load(); }

 private:
  using Clock = std::chrono::steady_clock;
  struct Connection {
    // The accept thread shuts the socket down to evict the connection; Serve closes it. The
    // mutex keeps the one from acting on a descriptor number the other has already closed.
    Mutex mutex;
    int fd GUARDED_BY(mutex) = -1;  // the client's socket (non-blocking); -1 once closed
    bool handshaking GUARDED_BY(mutex) = true;
    bool evicted GUARDED_BY(mutex) = false;
    std::string peer;               // "ip:port"
    Clock::time_point accepted_at;  // set before the thread starts, then only read
    std::thread thread;
    std::atomic<bool> done{false};  // set by Serve as it returns: the accept thread may join
  };
  enum FailureReason { kTimeout, kClosed, kCertificate, kProtocol, kEvicted, kReasonCount };

  TlsFront(int backend_port, TlsFrontOptions options);
  void AcceptLoop();
  void AcceptOne();
  void ReapFinished();
  // The oldest connection still in its handshake, old enough to be evicted when a newcomer
  // waits and every slot is taken; null when there is none (or an eviction is under way).
  // *ripe_in_ms: when the oldest one will be old enough (-1: no such connection).
  Connection* EvictionCandidate(int* ripe_in_ms);
  static void Evict(Connection* connection);
  // Runs on the connection's thread: handshake, then relay; closes the socket.
  void Serve(Connection* connection);
  struct Handshake {
    bool done = false;                     // completed
    FailureReason failure = kReasonCount;  // kReasonCount: none (done, or shutting down)
    std::string detail;                    // OpenSSL's reason for the failure
  };
  Handshake HandshakeWith(ssl_st* ssl, int client_fd) const;
  void RelayToBackend(ssl_st* ssl, int client_fd, Clock::time_point deadline) const;
  void RecordFailure(FailureReason reason, std::string detail, const std::string& peer) EXCLUDES(failures_mutex_);
  // Hands the pending failures to report_failures when due (or, with `force`, at once).
  void ReportFailures(bool force) EXCLUDES(failures_mutex_);
  // Milliseconds until pending failures are due for a report; -1 when none are pending.
  int MillisecondsToNextReport() const EXCLUDES(failures_mutex_);
  void Notify() const;

  const int backend_port_;
  const TlsFrontOptions options_;
  ssl_ctx_st* ctx_ = nullptr;
  int listen_fd_ = -1;
  int port_ = 0;
  int stop_fd_ = -1;    // eventfd, written once by the destructor and never read: every poll
                        // in every thread watches it and returns
  int notify_fd_ = -1;  // eventfd: a connection ended or a failure is pending; read by the
                        // accept loop
  Counter* failure_counters_[kReasonCount] = {};
  std::atomic<int64_t> total_failures_{0};
  std::thread accept_thread_;
  // Touched by the accept thread only (and by the destructor after joining it).
  std::list<std::unique_ptr<Connection>> connections_;

  mutable Mutex failures_mutex_;
  HandshakeFailureReport pending_ GUARDED_BY(failures_mutex_);  // failures == 0: none pending
  Clock::time_point next_report_at_ GUARDED_BY(failures_mutex_) = Clock::time_point::min();
};

}  // namespace localizer::server::metrics
