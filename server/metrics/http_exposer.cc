#include "server/metrics/http_exposer.h"

#include <civetweb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>

#include "server/metrics/listen_address.h"
#include "server/metrics/text_format.h"

namespace localizer::server::metrics {
namespace {

constexpr int kMaxThreads = 64;
// A connection that sends no complete request within this time is dropped: an idle or slow
// client holds one worker at most this long (at 10 s, four idle connections kept every
// scrape of a 2-thread server waiting past Prometheus's own timeout).
constexpr char kRequestTimeoutMs[] = "2000";

void InitCivetwebOnce() {
  static std::once_flag once;
  // Process-wide and never undone: mg_exit_library would break other users of civetweb.
  std::call_once(once, [] { mg_init_library(0); });
}

// Opens a TCP connection to `address` without waiting for it to complete, and closes it:
// enough to make a poll() on the listener return.
void PokeListener(const ListenAddress& address) {
  sockaddr_storage storage{};
  const socklen_t length = ToSockaddr(address, &storage);
  if (length == 0) return;
  const int fd = socket(storage.ss_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return;
  (void)connect(fd, reinterpret_cast<const sockaddr*>(&storage), length);  // EINPROGRESS is fine: the SYN wakes it
  close(fd);
}

// "host:port" -> the address, whose ToString() is civetweb's listening_ports syntax
// ("127.0.0.1:8080", "[::1]:8080"). The port is digits only: civetweb's "s" (TLS) and "r"
// (redirect) suffixes are refused. Its TLS cannot work against Debian 12's OpenSSL 3 (a
// handshake, then a crash on the first request; docs/SECURITY.md, "HTTP and TLS"): HTTPS is
// served by TlsFront (tls_front.h) in front of a loopback exposer instead.
StatusOr<ListenAddress> ToCivetwebListeningPort(const std::string& listen) {
  StatusOr<ListenAddress> address = ParseListenAddress(listen);
  if (!address.ok()) return address.status();
  if (address->ipv6() && mg_check_feature(MG_FEATURES_IPV6) == 0) {
    return InvalidArgument("listen address \"" + listen +
                           "\" is IPv6, which this civetweb build does not support (expected host:port, e.g. "
                           "127.0.0.1:9100 or [::1]:0)");
  }
  return address;
}

bool IsValidPagePath(const std::string& path) {
  if (path.empty() || path.front() != '/') return false;
  for (const char c : path) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '/' ||
                    c == '.' || c == '_' || c == '~' || c == '-';
    if (!ok) return false;
  }
  return true;
}

// Writes a complete response; `body` is omitted for HEAD but Content-Length still counts it.
int SendResponse(mg_connection* connection, int status, const std::string& content_type, const std::string& body,
                 bool head_only, const char* extra_headers = "") {
  mg_printf(connection,
            "HTTP/1.1 %d %s\r\n"
            "Content-Type: %s\r\n"
            "Content-Length: %zu\r\n"
            "Cache-Control: no-store\r\n"
            "%s"
            "Connection: close\r\n"
            "\r\n",
            status, mg_get_response_code_text(connection, status), content_type.c_str(), body.size(), extra_headers);
  if (!head_only && !body.empty()) mg_write(connection, body.data(), body.size());
  return status;
}

}  // namespace

HttpExposer::HttpExposer(Registry* registry) : registry_(registry) {}

HttpExposer::~HttpExposer() {
  if (context_ == nullptr) return;
  // mg_stop sets a flag that civetweb's listener thread reads only when its poll() returns,
  // which without traffic takes up to 2 s; connecting to ourselves makes it return at once.
  std::atomic<bool> stopped{false};
  std::thread waker;
  try {
    waker = std::thread([this, &stopped] {
      while (!stopped.load()) {
        PokeListener(wake_address_);
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    });
  } catch (const std::system_error&) {
    // No thread to spare: mg_stop still returns, within civetweb's 2 s poll step.
  }
  mg_stop(context_);  // joins civetweb's threads; pages_ is still alive meanwhile
  stopped.store(true);
  if (waker.joinable()) waker.join();
}

StatusOr<std::unique_ptr<HttpExposer>> HttpExposer::Start(const std::string& listen, Registry* registry, int threads) {
  if (registry == nullptr) return InvalidArgument("HttpExposer needs a registry, got null");
  if (threads < 1 || threads > kMaxThreads) {
    return InvalidArgument("HttpExposer threads is " + std::to_string(threads) + ", must be in 1.." +
                           std::to_string(kMaxThreads));
  }
  StatusOr<ListenAddress> address = ToCivetwebListeningPort(listen);
  if (!address.ok()) return address.status();
  const std::string listening_ports = address->ToString();
  InitCivetwebOnce();

  std::unique_ptr<HttpExposer> exposer(new HttpExposer(registry));
  const std::string num_threads = std::to_string(threads);
  // No document_root: civetweb serves no files; every request goes to HandleRequest.
  // clang-format off
  const char* options[] = {"listening_ports",    listening_ports.c_str(),
                           "num_threads",        num_threads.c_str(),
                           "request_timeout_ms", kRequestTimeoutMs,
                           "enable_keep_alive",  "no",
                           nullptr};
  // clang-format on
  mg_callbacks callbacks{};
  callbacks.begin_request = &HttpExposer::HandleRequest;
  callbacks.log_message = &HttpExposer::LogMessage;
  mg_init_data init{};
  init.callbacks = &callbacks;
  init.user_data = exposer.get();
  init.configuration_options = options;
  char error_text[256] = "";
  unsigned error_code = 0;
  mg_error_data error{};
  error.code = &error_code;
  error.text = error_text;
  error.text_buffer_size = sizeof error_text;

  exposer->context_ = mg_start2(&init, &error);
  std::string log;
  {
    MutexLock lock(&exposer->log_mutex_);
    exposer->starting_ = false;
    log = std::move(exposer->startup_log_);
  }
  if (exposer->context_ == nullptr) {
    // The log says why ("cannot bind to ...: Address already in use"); it ends with the
    // summary mg_start2 also returns in error_text.
    const std::string reason = !log.empty()            ? log
                               : error_text[0] != '\0' ? std::string(error_text)
                                                       : "civetweb failed to start";
    return Status(StatusCode::kUnavailable, "cannot serve metrics on \"" + listen + "\": " + reason);
  }
  const std::string& host = address->host;
  exposer->wake_address_.host = host == "0.0.0.0" ? "127.0.0.1" : host == "[::]" ? "[::1]" : host;
  mg_server_port ports[4];
  std::memset(ports, 0, sizeof ports);
  const int port_count = mg_get_server_ports(exposer->context_, 4, ports);
  if (port_count < 1 || ports[0].port <= 0) {
    return Internal("civetweb started on \"" + listen + "\" but reports no listening port");
  }
  exposer->port_ = ports[0].port;
  exposer->wake_address_.port = exposer->port_;
  return exposer;
}

Status HttpExposer::AddPage(const std::string& path, PageHandler handler, std::string content_type, PageGuard guard) {
  if (!IsValidPagePath(path)) {
    return InvalidArgument("page path \"" + path + "\" must start with '/' and use only [A-Za-z0-9/._~-]");
  }
  if (!handler) return InvalidArgument("page \"" + path + "\" has an empty handler");
  if (content_type.empty()) return InvalidArgument("page \"" + path + "\" has no content type");
  for (const char c : content_type) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      return InvalidArgument("content type of page \"" + path + "\" holds a control character");
    }
  }
  MutexLock lock(&pages_mutex_);
  pages_[path] = Page{std::move(handler), std::move(content_type), std::move(guard)};
  return Status::Ok();
}

bool HttpExposer::FindPage(const std::string& path, Page* page) const {
  MutexLock lock(&pages_mutex_);
  const auto it = pages_.find(path);
  if (it != pages_.end()) {
    *page = it->second;
    return true;
  }
  if (path == "/metrics") {
    page->handler = [this] { return std::pair<int, std::string>(200, registry_->Serialize()); };
    page->content_type = kTextFormatContentType;
    return true;
  }
  if (path == "/") {
    page->handler = [this] { return std::pair<int, std::string>(200, IndexPage()); };
    page->content_type = "text/html; charset=utf-8";
    return true;
  }
  return false;
}

std::string HttpExposer::IndexPage() const {
  std::string html =
      "<!DOCTYPE html>\n<html><head><title>localizer</title></head><body>\n"
      "<h1>localizer</h1>\n<ul>\n<li><a href=\"/metrics\">/metrics</a></li>\n";
  MutexLock lock(&pages_mutex_);
  for (const auto& [path, page] : pages_) {
    if (path == "/" || path == "/metrics") continue;
    // Paths hold only [A-Za-z0-9/._~-] (AddPage checks), so they need no HTML escaping.
    html += "<li><a href=\"" + path + "\">" + path + "</a></li>\n";
  }
  html += "</ul>\n</body></html>\n";
  return html;
}

int HttpExposer::LogMessage(const mg_connection* connection, const char* message) {
  // Once serving, civetweb logs per-connection noise (clients hanging up): dropped.
  if (connection == nullptr || message == nullptr) return 1;
  const mg_context* context = mg_get_context(connection);
  auto* self = context != nullptr ? static_cast<HttpExposer*>(mg_get_user_data(context)) : nullptr;
  if (self == nullptr) return 1;
  MutexLock lock(&self->log_mutex_);
  if (self->starting_ && self->startup_log_.size() < 1024) {
    if (!self->startup_log_.empty()) self->startup_log_ += "; ";
    self->startup_log_ += message;
  }
  return 1;
}

int HttpExposer::HandleRequest(mg_connection* connection) {
  // Exceptions must not unwind through civetweb's C frames: everything is caught here.
  try {
    auto* self = static_cast<HttpExposer*>(mg_get_user_data(mg_get_context(connection)));
    const mg_request_info* request = mg_get_request_info(connection);
    const std::string method = request->request_method != nullptr ? request->request_method : "";
    const std::string path = request->local_uri != nullptr ? request->local_uri : "";
    const bool head_only = method == "HEAD";

    Page page;
    if (!self->FindPage(path, &page)) {
      return SendResponse(connection, 404, "text/plain; charset=utf-8", "404 not found\n", head_only);
    }
    if (method != "GET" && !head_only) {
      return SendResponse(connection, 405, "text/plain; charset=utf-8",
                          "405 method not allowed: " + method + " (use GET or HEAD)\n", false, "Allow: GET, HEAD\r\n");
    }
    if (page.guard) {
      Credentials credentials;
      if (const char* header = mg_get_header(connection, "Authorization")) credentials.authorization = header;
      if (request->query_string != nullptr) {
        char token[4200];
        const int n =
            mg_get_var(request->query_string, std::strlen(request->query_string), "token", token, sizeof token);
        if (n > 0) credentials.query_token.assign(token, static_cast<size_t>(n));
      }
      const int refused = page.guard(credentials);
      if (refused == 401) {
        return SendResponse(connection, 401, "text/plain; charset=utf-8",
                            "401 unauthorized: send 'Authorization: Bearer TOKEN' (an operator token)\n", head_only,
                            "WWW-Authenticate: Bearer realm=\"localizer\"\r\n");
      }
      if (refused != 0) {
        return SendResponse(connection, 403, "text/plain; charset=utf-8",
                            "403 forbidden: this page needs an operator token\n", head_only);
      }
    }
    std::pair<int, std::string> result;
    try {
      result = page.handler();
    } catch (const std::exception& e) {
      return SendResponse(connection, 500, "text/plain; charset=utf-8",
                          std::string("500 page handler failed: ") + e.what() + "\n", head_only);
    }
    if (result.first < 100 || result.first > 599) {
      return SendResponse(connection, 500, "text/plain; charset=utf-8",
                          "500 page handler returned status " + std::to_string(result.first) + "\n", head_only);
    }
    return SendResponse(connection, result.first, page.content_type, result.second, head_only);
  } catch (...) {
    mg_printf(connection,
              "HTTP/1.1 500 Internal Server Error\r\nContent-Length: 0\r\n"
              "Connection: close\r\n\r\n");
    return 500;
  }
}

}  // namespace localizer::server::metrics
