// HttpExposer: a small HTTP server (civetweb) that serves a Registry to Prometheus.
// Plaintext only; for HTTPS, start it on 127.0.0.1:0 and put a TlsFront (tls_front.h) on the
// public address.
//
//   GET/HEAD /metrics  200, Registry::Serialize() as
//                      "text/plain; version=0.0.4; charset=utf-8"
//   GET/HEAD /         200, a short HTML index linking /metrics and every added page
//   GET/HEAD <page>    whatever a handler given to AddPage returns (e.g. /healthz), or
//                      401/403 when the page's guard refuses the request
//   other paths        404
//   other methods      405 with "Allow: GET, HEAD" (on a known path)
// The query string is ignored (except a guard's `token`). No files are ever served (civetweb runs without a document
// root). Connections are closed after each response (no keep-alive); a request that does
// not arrive within 2 s is dropped, and 8 workers by default serve at once, so a few idle
// or slow connections cannot keep scrapes from being answered.
//
// Lifetime: Start binds and starts `threads` worker threads; the destructor stops the
// server, waiting for requests in flight (civetweb's listener polls in 2 s steps; the
// destructor wakes it with a local connection, so stopping takes milliseconds). The
// Registry (and anything the page handlers use) must outlive the HttpExposer.
//
// Thread-safety: port() and AddPage may be called from any thread at any time. Requests are
// served concurrently by the worker threads, so Registry::Serialize (thread-safe) and page
// handlers may run in parallel with each other and with the rest of the program.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "engine/core/status.h"
#include "server/metrics/listen_address.h"
#include "server/metrics/registry.h"
#include "server/sync/mutex.h"

struct mg_connection;
struct mg_context;

namespace localizer::server::metrics {

class HttpExposer final {
 public:
  // Returns {HTTP status code (100..599), body}. Runs on a worker thread for every request
  // to its path; must be thread-safe and quick. An exception escaping it becomes a 500.
  using PageHandler = std::function<std::pair<int, std::string>()>;

  // What a page's guard sees of a request: the Authorization header ("" when absent) and the
  // query string's `token` parameter (URL-decoded; "" when absent).
  struct Credentials {
    std::string authorization;
    std::string query_token;
  };
  // Decides whether a request may see a page: 0 to serve it, else 401 (answered with
  // "WWW-Authenticate: Bearer") or 403; anything else is taken as 403. Runs on a worker
  // thread before the handler; must be thread-safe and quick.
  using PageGuard = std::function<int(const Credentials&)>;

  // Listens on `listen`, "host:port": host is an IPv4 literal ("127.0.0.1", "0.0.0.0" for
  // every interface), a bracketed IPv6 literal ("[::1]", if civetweb was built with IPv6)
  // or "localhost" (127.0.0.1); port is 0..65535, 0 picking a free ephemeral port (read
  // it back with port()). `threads` (1..64) requests are served at once.
  // Errors: INVALID_ARGUMENT for a malformed address, a null registry or a thread count out
  // of range; UNAVAILABLE when the server cannot start (port in use, address not local,
  // permission denied), with the address and civetweb's reason in the message.
  static StatusOr<std::unique_ptr<HttpExposer>> Start(const std::string& listen, Registry* registry, int threads = 8);

  ~HttpExposer();
  HttpExposer(const HttpExposer&) = delete;
  HttpExposer& operator=(const HttpExposer&) = delete;

  // The TCP port the server listens on (the chosen one when Start was given port 0).
  int port() const { return port_; }

  // Serves `handler`'s result at `path` (exact match) with the given Content-Type,
  // replacing any page already there, /metrics and / included. INVALID_ARGUMENT when path
  // does not start with '/' or holds characters other than [A-Za-z0-9/._~-], or when
  // content_type is empty or holds a control character; nothing changes then.
  // A `guard` (optional) runs before the handler and may refuse the request (401/403, with
  // a short plain-text body that never echoes the credentials).
  Status AddPage(const std::string& path, PageHandler handler, std::string content_type, PageGuard guard = nullptr)
      EXCLUDES(pages_mutex_);

 private:
  struct Page {
    PageHandler handler;
    std::string content_type;
    PageGuard guard;  // empty: open
  };

  explicit HttpExposer(Registry* registry);
  // civetweb's begin_request callback: answers every request; returns the status sent.
  static int HandleRequest(mg_connection* connection);
  // civetweb's log_message callback: keeps what civetweb logs while Start runs (the reason
  // a port could not be bound) for Start's error message; drops everything later.
  static int LogMessage(const mg_connection* connection, const char* message);
  // Copies the page served at `path` into *page; false if there is none ("/" is the
  // index unless a page replaced it).
  bool FindPage(const std::string& path, Page* page) const EXCLUDES(pages_mutex_);
  std::string IndexPage() const EXCLUDES(pages_mutex_);

  Registry* const registry_;
  mg_context* context_ = nullptr;
  int port_ = 0;
  // An address of the listening socket that this process can connect to (loopback for a
  // wildcard listen address); the destructor connects there to wake civetweb's listener.
  ListenAddress wake_address_;

  Mutex log_mutex_;
  bool starting_ GUARDED_BY(log_mutex_) = true;
  std::string startup_log_ GUARDED_BY(log_mutex_);

  mutable Mutex pages_mutex_;
  std::map<std::string, Page> pages_ GUARDED_BY(pages_mutex_);  // path -> page
};

}  // namespace localizer::server::metrics
