// TlsFront (server/metrics/tls_front.h) in front of an HttpExposer on loopback: HTTPS and
// mutual TLS, plain HTTP and garbage refused, idle, stalled and trickling clients bounded,
// failures counted and reported, shutdown. The clients are OpenSSL in C++
// (tests/server/https_client.h); the PKI comes from deploy/tls/make_test_certs.sh (without the
// openssl CLI the tests skip with the reason). Uses the metrics library only (with civetweb
// and OpenSSL), so it can be built and run alone, e.g. under TSan.
#include "server/metrics/tls_front.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "server/metrics/http_exposer.h"
#include "tests/server/http_client.h"
#include "tests/server/https_client.h"
#include "tests/server/test_pki.h"

namespace localizer::server::metrics {
namespace {

using Clock = std::chrono::steady_clock;
using ::localizer::testing::HttpsRequest;
using ::localizer::testing::HttpsResponse;
using ::localizer::testing::Pki;
using ::localizer::testing::TlsClientOptions;
using ::localizer::testing::TlsConnection;

double SecondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// An idle plain TCP connection to 127.0.0.1:port (no TLS, no request); -1 on failure.
int ConnectTcp(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

// --- TlsFront in front of an HttpExposer -------------------------------------------------

class TlsFrontTest : public ::testing::Test {
 protected:
  void SetUp() override {
    registry_.AddCounter("test_blocks_total", "Blocks seen.", {"backend"})
        .value()
        ->WithLabels({"cpu"})
        .value()
        ->Increment(42);
    failures_ = registry_.AddCounter("test_handshake_failures_total", "Failed handshakes.", {"reason"}).value();
    auto exposer = HttpExposer::Start("127.0.0.1:0", &registry_);
    ASSERT_TRUE(exposer.ok()) << exposer.status().ToString();
    exposer_ = std::move(*exposer);
  }
  void TearDown() override { front_.reset(); }  // before the exposer

  TlsFrontOptions Options(bool mutual = false) const {
    TlsFrontOptions options;
    options.cert_chain_pem = pki_.Pem("server.crt");
    options.key_pem = pki_.Pem("server.key");
    if (mutual) options.client_ca_pem = pki_.Pem("ca.crt");
    options.handshake_failures = failures_;
    return options;
  }
  void StartFront(TlsFrontOptions options) {
    auto front = TlsFront::Start("127.0.0.1:0", exposer_->port(), std::move(options));
    ASSERT_TRUE(front.ok()) << front.status().ToString();
    front_ = std::move(*front);
    ASSERT_GT(front_->port(), 0);
    ASSERT_NE(front_->port(), exposer_->port());
  }
  TlsClientOptions Trusting() const {
    TlsClientOptions client;
    client.ca_file = pki_.Cert("ca.crt");
    return client;
  }
  HttpsResponse Get(const std::string& path, const TlsClientOptions& client) {
    return HttpsRequest(front_->port(), "GET", path, client);
  }
  double Failures(const std::string& reason) const { return failures_->WithLabels({reason}).value()->value(); }

  Pki pki_;
  Registry registry_;
  Family<Counter>* failures_ = nullptr;
  std::unique_ptr<HttpExposer> exposer_;
  std::unique_ptr<TlsFront> front_;
};

TEST_F(TlsFrontTest, ServesMetricsToAClientThatTrustsTheCa) {
  SKIP_WITHOUT_PKI();
  StartFront(Options());
  const HttpsResponse r = Get("/metrics", Trusting());
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.status_line, "HTTP/1.1 200 OK");
  EXPECT_EQ(r.headers.at("content-type"), "text/plain; version=0.0.4; charset=utf-8");
  EXPECT_EQ(r.headers.at("content-length"), std::to_string(r.body.size()));
  EXPECT_NE(r.body.find("test_blocks_total{backend=\"cpu\"} 42\n"), std::string::npos) << r.body;
  // The SAN's IP address verifies as well as its DNS name; 404s pass through.
  TlsClientOptions by_ip = Trusting();
  by_ip.server_name = "127.0.0.1";
  EXPECT_EQ(Get("/nope", by_ip).status, 404);
  EXPECT_EQ(front_->handshake_failures(), 0);
}

TEST_F(TlsFrontTest, ClientThatDoesNotTrustTheCaFailsTheHandshake) {
  SKIP_WITHOUT_PKI();
  ASSERT_TRUE(pki_.Make("other"));
  StartFront(Options());
  TlsClientOptions other;
  other.ca_file = pki_.Cert("ca.crt", "other");
  const HttpsResponse r = Get("/metrics", other);
  EXPECT_FALSE(r.handshake_ok);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("certificate verify failed"), std::string::npos) << r.error;
  TlsClientOptions wrong_name = Trusting();
  wrong_name.server_name = "localizer.example";  // not in the certificate's SAN
  EXPECT_FALSE(Get("/metrics", wrong_name).handshake_ok);
  EXPECT_EQ(Get("/metrics", Trusting()).status, 200);
}

TEST_F(TlsFrontTest, PlainHttpAndGarbageGetNoHttpAnswerAndServingGoesOn) {
  SKIP_WITHOUT_PKI();
  StartFront(Options());
  const auto plain = ::localizer::testing::Request(front_->port(), "GET", "/metrics");
  EXPECT_FALSE(plain.ok);
  EXPECT_EQ(plain.status, 0);
  std::string garbage(4096, '\0');
  for (size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<char>((i * 7919 + 13) & 0xff);
  EXPECT_FALSE(::localizer::testing::RawRequest(front_->port(), garbage).ok);
  // A TLS record header announcing a huge record, then nothing.
  EXPECT_FALSE(::localizer::testing::RawRequest(front_->port(), std::string("\x16\x03\x01\xff\xff", 5)).ok);
  const HttpsResponse r = Get("/metrics", Trusting());
  EXPECT_EQ(r.status, 200) << r.error;
  EXPECT_GE(Failures("protocol"), 2.0);
  EXPECT_EQ(front_->handshake_failures(), 3);
}

TEST_F(TlsFrontTest, MutualTlsRefusesClientsWithoutACertificateFromTheCa) {
  SKIP_WITHOUT_PKI();
  ASSERT_TRUE(pki_.Make("other"));
  StartFront(Options(/*mutual=*/true));
  // Under TLS 1.3 the client's side of the handshake completes before the server has checked
  // its certificate; the refusal then arrives as an alert instead of the response.
  const HttpsResponse none = Get("/metrics", Trusting());
  EXPECT_FALSE(none.ok);
  EXPECT_EQ(none.status, 0);
  TlsClientOptions foreign = Trusting();
  foreign.cert_file = pki_.Cert("client.crt", "other");
  foreign.key_file = pki_.Cert("client.key", "other");
  EXPECT_FALSE(Get("/metrics", foreign).ok);
  TlsClientOptions with_cert = Trusting();
  with_cert.cert_file = pki_.Cert("client.crt");
  with_cert.key_file = pki_.Cert("client.key");
  const HttpsResponse r = Get("/metrics", with_cert);
  EXPECT_EQ(r.status, 200) << r.error;
  EXPECT_EQ(Failures("certificate"), 2.0);
}

TEST_F(TlsFrontTest, ServesConcurrentClients) {
  SKIP_WITHOUT_PKI();
  StartFront(Options());
  std::atomic<int> good{0};
  std::vector<std::thread> clients;
  const TlsClientOptions client = Trusting();
  for (int c = 0; c < 6; ++c) {
    clients.emplace_back([&] {
      for (int i = 0; i < 10; ++i) {
        const HttpsResponse r = HttpsRequest(front_->port(), "GET", "/metrics", client);
        if (r.status == 200 && r.body == registry_.Serialize()) ++good;
      }
    });
  }
  for (auto& thread : clients) thread.join();
  EXPECT_EQ(good.load(), 60);
}

// A response far larger than the relay's buffers arrives whole (backpressure, not loss).
TEST_F(TlsFrontTest, LargeResponsesPassThroughTheBoundedBuffers) {
  SKIP_WITHOUT_PKI();
  std::string big(3 << 20, 'x');
  for (size_t i = 0; i < big.size(); i += 64) big[i] = static_cast<char>('a' + (i / 64) % 26);
  ASSERT_TRUE(exposer_
                  ->AddPage(
                      "/big", [big] { return std::pair(200, big); }, "text/plain")
                  .ok());
  TlsFrontOptions options = Options();
  options.buffer_bytes = 1024;
  StartFront(std::move(options));
  const HttpsResponse r = Get("/big", Trusting());
  EXPECT_EQ(r.status, 200) << r.error;
  EXPECT_TRUE(r.body == big) << r.body.size() << " bytes";
}

// Twelve handshaken connections that send no request hold civetweb's 8 workers until its 2 s
// request timeout, as idle plaintext connections do (metrics_http_test.cc): scrapes are still
// answered within a few seconds.
TEST_F(TlsFrontTest, ScrapesAreAnsweredWhileIdleTlsConnectionsHoldTheWorkers) {
  SKIP_WITHOUT_PKI();
  StartFront(Options());
  std::vector<std::unique_ptr<TlsConnection>> idle;
  for (int i = 0; i < 12; ++i) {
    idle.push_back(std::make_unique<TlsConnection>(front_->port(), Trusting()));
    ASSERT_TRUE(idle.back()->ok()) << idle.back()->error();
  }
  for (int scrape = 0; scrape < 3; ++scrape) {
    const auto start = Clock::now();
    const HttpsResponse r = Get("/metrics", Trusting());
    EXPECT_EQ(r.status, 200) << r.error;
    EXPECT_LT(SecondsSince(start), 4.0) << "scrape " << scrape;
  }
}

// Forty idle TCP connections (no handshake), more than twice the front's 16 slots: the
// oldest still handshaking are evicted when a newcomer waits, so a scrape behind them waits
// about a second, not the 3 x 2 s of handshake timeouts the queue alone would take.
TEST_F(TlsFrontTest, ScrapesAreAnsweredWhileIdleTcpConnectionsFillTheFront) {
  SKIP_WITHOUT_PKI();
  StartFront(Options());
  std::vector<int> idle;
  for (int i = 0; i < 40; ++i) {
    const int fd = ConnectTcp(front_->port());  // the kernel completes it from the backlog
    ASSERT_GE(fd, 0);
    idle.push_back(fd);
  }
  for (int scrape = 0; scrape < 3; ++scrape) {
    const auto start = Clock::now();
    const HttpsResponse r = Get("/metrics", Trusting());
    EXPECT_EQ(r.status, 200) << r.error;
    EXPECT_LT(SecondsSince(start), 3.0) << "scrape " << scrape;
  }
  for (int fd : idle) close(fd);
  EXPECT_GE(Failures("evicted") + Failures("timeout"), 16.0);
}

TEST_F(TlsFrontTest, HandshakeTimeoutClosesASilentConnection) {
  SKIP_WITHOUT_PKI();
  StartFront(Options());
  const int fd = ConnectTcp(front_->port());
  ASSERT_GE(fd, 0);
  const auto start = Clock::now();
  char byte;
  timeval timeout{10, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  EXPECT_EQ(recv(fd, &byte, 1, 0), 0);  // closed by the front, without a byte
  const double waited_s = SecondsSince(start);
  close(fd);
  EXPECT_GT(waited_s, 1.5);
  EXPECT_LT(waited_s, 4.0);
  EXPECT_EQ(Failures("timeout"), 1.0);
}

// A client that sends a request and stops reading holds its slot only until the idle
// timeout: with one slot, the next scrape is answered once it is dropped.
TEST_F(TlsFrontTest, ClientThatStopsReadingIsDroppedAfterTheIdleTimeout) {
  SKIP_WITHOUT_PKI();
  const std::string big(16 << 20, 'x');
  ASSERT_TRUE(exposer_
                  ->AddPage(
                      "/big", [&big] { return std::pair(200, big); }, "text/plain")
                  .ok());
  TlsFrontOptions options = Options();
  options.max_connections = 1;
  options.idle_timeout_s = 1.0;
  StartFront(std::move(options));
  TlsConnection stalled(front_->port(), Trusting());
  ASSERT_TRUE(stalled.ok()) << stalled.error();
  ASSERT_TRUE(stalled.Send("GET /big HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n"));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the front is now blocked writing to it
  const auto start = Clock::now();
  const HttpsResponse r = Get("/metrics", Trusting());
  const double waited_s = SecondsSince(start);
  EXPECT_EQ(r.status, 200) << r.error;
  EXPECT_GT(waited_s, 0.5);  // it waited in the backlog for the one slot
  EXPECT_LT(waited_s, 4.0);
  // What the stalled client can still read is what the buffers held, not the whole page.
  const HttpsResponse cut = stalled.Receive();
  EXPECT_LT(cut.body.size(), big.size());
}

// A request trickled a byte at a time keeps the idle timeout from firing; the connection's
// lifetime cap ends it (here 1 s, before civetweb's own 2 s request timeout).
TEST_F(TlsFrontTest, TrickledRequestIsCutAtTheConnectionLifetime) {
  SKIP_WITHOUT_PKI();
  TlsFrontOptions options = Options();
  options.max_connection_s = 1.0;
  StartFront(std::move(options));
  TlsConnection trickle(front_->port(), Trusting());
  ASSERT_TRUE(trickle.ok()) << trickle.error();
  const auto start = Clock::now();
  const std::string request = "GET /metrics HTTP/1.1\r\nHost: localhost\r\nX-Padding: ";
  bool closed = false;
  for (size_t i = 0; SecondsSince(start) < 5.0 && !closed; ++i) {
    (void)trickle.Send(std::string(1, i < request.size() ? request[i] : 'x'));
    pollfd fd{trickle.fd(), POLLIN, 0};
    closed = poll(&fd, 1, 200) > 0;  // the front says nothing until it closes
  }
  const double lived_s = SecondsSince(start);
  EXPECT_TRUE(closed);
  EXPECT_GT(lived_s, 0.8);
  EXPECT_LT(lived_s, 1.8);
  EXPECT_EQ(Get("/metrics", Trusting()).status, 200);
}

TEST_F(TlsFrontTest, FailuresAreReportedAtMostOncePerInterval) {
  SKIP_WITHOUT_PKI();
  std::mutex mutex;
  std::vector<HandshakeFailureReport> reports;
  TlsFrontOptions options = Options();
  options.report_interval_s = 1.0;
  options.report_failures = [&](const HandshakeFailureReport& report) {
    std::lock_guard<std::mutex> lock(mutex);
    reports.push_back(report);
  };
  StartFront(std::move(options));
  const auto count = [&] {
    std::lock_guard<std::mutex> lock(mutex);
    return reports.size();
  };
  for (int i = 0; i < 5; ++i) (void)::localizer::testing::Request(front_->port(), "GET", "/metrics");
  for (int i = 0; i < 100 && count() < 2; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  {
    std::lock_guard<std::mutex> lock(mutex);
    ASSERT_EQ(reports.size(), 2u);  // the first at once, the other four summed a second later
    EXPECT_EQ(reports[0].failures, 1);
    EXPECT_EQ(reports[1].failures, 4);
    EXPECT_EQ(reports[1].last_reason, "protocol");
    EXPECT_NE(reports[1].last_detail.find("http request"), std::string::npos) << reports[1].last_detail;
    EXPECT_EQ(reports[1].last_peer.rfind("127.0.0.1:", 0), 0u) << reports[1].last_peer;
  }
  // One more, then the destructor reports it without waiting for the interval.
  (void)::localizer::testing::Request(front_->port(), "GET", "/metrics");
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  front_.reset();
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_EQ(reports.size(), 3u);
  EXPECT_EQ(reports[2].failures, 1);
}

TEST_F(TlsFrontTest, DestructorClosesOpenConnectionsAndStopsServing) {
  SKIP_WITHOUT_PKI();
  StartFront(Options());
  const int port = front_->port();
  TlsConnection idle_tls(port, Trusting());
  ASSERT_TRUE(idle_tls.ok());
  const int idle_tcp = ConnectTcp(port);
  ASSERT_GE(idle_tcp, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const auto start = Clock::now();
  front_.reset();
  EXPECT_LT(SecondsSince(start), 1.0);
  close(idle_tcp);
  EXPECT_LT(ConnectTcp(port), 0);  // nothing listens there any more
}

TEST(TlsFrontStart, RefusesBadArgumentsWithAStatus) {
  if (!Pki::HaveOpenssl()) GTEST_SKIP() << "the openssl CLI is not installed (Debian: openssl): no test PKI";
  Pki pki;
  ASSERT_TRUE(pki.Make("pki"));
  ASSERT_TRUE(pki.Make("other"));
  TlsFrontOptions good;
  good.cert_chain_pem = pki.Pem("server.crt");
  good.key_pem = pki.Pem("server.key");
  const auto code = [](const std::string& listen, int backend, const TlsFrontOptions& options) {
    return TlsFront::Start(listen, backend, options).status().code();
  };
  EXPECT_EQ(code("127.0.0.1:0", 9, good), StatusCode::kOk);
  for (const char* listen : {"", "9100", "127.0.0.1:65536", "example.com:443", "[zz]:1"}) {
    const auto status = TlsFront::Start(listen, 9, good).status();
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << listen;
    EXPECT_NE(status.message().find(std::string("\"") + listen + "\""), std::string::npos) << status.message();
  }
  EXPECT_EQ(code("127.0.0.1:0", 0, good), StatusCode::kInvalidArgument);
  TlsFrontOptions o = good;
  o.max_connections = 0;
  EXPECT_EQ(code("127.0.0.1:0", 9, o), StatusCode::kInvalidArgument);
  o = good;
  o.handshake_timeout_s = 0;
  EXPECT_EQ(code("127.0.0.1:0", 9, o), StatusCode::kInvalidArgument);
  o = good;
  o.buffer_bytes = 10;
  EXPECT_EQ(code("127.0.0.1:0", 9, o), StatusCode::kInvalidArgument);
  o = good;
  o.cert_chain_pem = "not PEM";
  EXPECT_EQ(code("127.0.0.1:0", 9, o), StatusCode::kInvalidArgument);
  o = good;
  o.key_pem = pki.Pem("server.key", "other");
  auto status = TlsFront::Start("127.0.0.1:0", 9, o).status();
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("not the key"), std::string::npos) << status.message();
  o = good;
  o.client_ca_pem = "-----BEGIN CERTIFICATE-----\nnope\n-----END CERTIFICATE-----\n";
  EXPECT_EQ(code("127.0.0.1:0", 9, o), StatusCode::kInvalidArgument);

  auto first = TlsFront::Start("127.0.0.1:0", 9, good);
  ASSERT_TRUE(first.ok());
  const std::string taken = "127.0.0.1:" + std::to_string((*first)->port());
  status = TlsFront::Start(taken, 9, good).status();
  EXPECT_EQ(status.code(), StatusCode::kUnavailable);
  EXPECT_NE(status.message().find(taken), std::string::npos) << status.message();
  EXPECT_EQ(code("192.0.2.1:0", 9, good), StatusCode::kUnavailable);  // TEST-NET-1: not local
}

}  // namespace
}  // namespace localizer::server::metrics
