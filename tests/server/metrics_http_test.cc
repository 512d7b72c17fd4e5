// HttpExposer (server/metrics/http_exposer.h) over loopback, with the plain POSIX-socket
// client of tests/server/http_client.h (no curl): status lines, the text-format
// Content-Type, bodies, 404/405, extra pages, and start-up failures returned as statuses.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "server/metrics/http_exposer.h"
#include "tests/server/http_client.h"

namespace localizer::server::metrics {
namespace {

using ::localizer::testing::HttpResponse;
using ::localizer::testing::RawRequest;
using ::localizer::testing::Request;

class HttpExposerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    Family<Counter>* blocks = registry_.AddCounter("test_blocks_total", "Blocks seen.", {"backend"}).value();
    blocks->WithLabels({"cpu"}).value()->Increment(42);
    auto exposer = HttpExposer::Start("127.0.0.1:0", &registry_);
    ASSERT_TRUE(exposer.ok()) << exposer.status().ToString();
    exposer_ = std::move(*exposer);
    ASSERT_GT(exposer_->port(), 0);
  }

  Registry registry_;
  std::unique_ptr<HttpExposer> exposer_;
};

TEST_F(HttpExposerTest, ServesMetricsInTheTextFormat) {
  const HttpResponse r = Request(exposer_->port(), "GET", "/metrics");
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.status_line, "HTTP/1.1 200 OK");
  EXPECT_EQ(r.headers.at("content-type"), "text/plain; version=0.0.4; charset=utf-8");
  EXPECT_EQ(r.headers.at("content-length"), std::to_string(r.body.size()));
  EXPECT_EQ(r.body,
            "# HELP test_blocks_total Blocks seen.\n"
            "# TYPE test_blocks_total counter\n"
            "test_blocks_total{backend=\"cpu\"} 42\n");
}

TEST_F(HttpExposerTest, QueryStringIsIgnored) {
  const HttpResponse r = Request(exposer_->port(), "GET", "/metrics?x=1");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, registry_.Serialize());
}

TEST_F(HttpExposerTest, EachScrapeRunsTheCollectors) {
  Gauge* scrapes = registry_.AddGauge("test_scrapes", "Scrapes.").value()->WithLabels({}).value();
  registry_.AddCollector([scrapes] { scrapes->Increment(); });
  EXPECT_NE(Request(exposer_->port(), "GET", "/metrics").body.find("test_scrapes 1\n"), std::string::npos);
  EXPECT_NE(Request(exposer_->port(), "GET", "/metrics").body.find("test_scrapes 2\n"), std::string::npos);
}

TEST_F(HttpExposerTest, HeadSendsHeadersWithoutBody) {
  const HttpResponse r = Request(exposer_->port(), "HEAD", "/metrics");
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.headers.at("content-length"), std::to_string(registry_.Serialize().size()));
  EXPECT_TRUE(r.body.empty());
}

TEST_F(HttpExposerTest, UnknownPathIs404) {
  for (const char* path : {"/nope", "/metrics/x", "/metricsx", "/../etc/passwd"}) {
    const HttpResponse r = Request(exposer_->port(), "GET", path);
    ASSERT_TRUE(r.ok) << path;
    EXPECT_EQ(r.status, 404) << path;
  }
}

TEST_F(HttpExposerTest, OtherMethodsAre405WithAllow) {
  for (const char* method : {"POST", "PUT", "DELETE"}) {
    const HttpResponse r = RawRequest(exposer_->port(), std::string(method) +
                                                            " /metrics HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n"
                                                            "Connection: close\r\n\r\n");
    ASSERT_TRUE(r.ok) << method;
    EXPECT_EQ(r.status, 405) << method;
    EXPECT_EQ(r.headers.at("allow"), "GET, HEAD");
  }
}

TEST_F(HttpExposerTest, IndexLinksMetricsAndAddedPages) {
  ASSERT_TRUE(exposer_
                  ->AddPage(
                      "/healthz", [] { return std::pair(200, std::string("ok\n")); }, "text/plain; charset=utf-8")
                  .ok());
  const HttpResponse r = Request(exposer_->port(), "GET", "/");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.headers.at("content-type"), "text/html; charset=utf-8");
  EXPECT_NE(r.body.find("<a href=\"/metrics\">"), std::string::npos);
  EXPECT_NE(r.body.find("<a href=\"/healthz\">"), std::string::npos);
}

TEST_F(HttpExposerTest, AddedPagesServeTheirHandlersStatusAndType) {
  std::atomic<bool> healthy{true};
  ASSERT_TRUE(exposer_
                  ->AddPage(
                      "/healthz",
                      [&healthy] {
                        return healthy ? std::pair(200, std::string("ok\n"))
                                       : std::pair(503, std::string("draining\n"));
                      },
                      "text/plain; charset=utf-8")
                  .ok());
  HttpResponse r = Request(exposer_->port(), "GET", "/healthz");
  EXPECT_EQ(r.status_line, "HTTP/1.1 200 OK");
  EXPECT_EQ(r.headers.at("content-type"), "text/plain; charset=utf-8");
  EXPECT_EQ(r.body, "ok\n");
  healthy = false;
  r = Request(exposer_->port(), "GET", "/healthz");
  EXPECT_EQ(r.status, 503);
  EXPECT_EQ(r.body, "draining\n");

  ASSERT_TRUE(exposer_
                  ->AddPage(
                      "/boom", []() -> std::pair<int, std::string> { throw std::runtime_error("kaput"); }, "text/plain")
                  .ok());
  EXPECT_EQ(Request(exposer_->port(), "GET", "/boom").status, 500);
  ASSERT_TRUE(exposer_
                  ->AddPage(
                      "/odd", [] { return std::pair(42, std::string()); }, "text/plain")
                  .ok());
  EXPECT_EQ(Request(exposer_->port(), "GET", "/odd").status, 500);
}

TEST_F(HttpExposerTest, AddPageRejectsBadPathsAndContentTypes) {
  const auto handler = [] { return std::pair(200, std::string()); };
  for (const char* path : {"", "healthz", "/a b", "/a?b", "/<x>", "/a\"b"}) {
    EXPECT_EQ(exposer_->AddPage(path, handler, "text/plain").code(), StatusCode::kInvalidArgument) << path;
  }
  EXPECT_EQ(exposer_->AddPage("/x", handler, "").code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(exposer_->AddPage("/x", handler, "text/plain\r\nX-Evil: 1").code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(exposer_->AddPage("/x", nullptr, "text/plain").code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(Request(exposer_->port(), "GET", "/x").status, 404);
}

TEST_F(HttpExposerTest, ServesConcurrentClients) {
  std::atomic<int> good{0};
  std::vector<std::thread> clients;
  for (int c = 0; c < 6; ++c) {
    clients.emplace_back([&] {
      for (int i = 0; i < 10; ++i) {
        const HttpResponse r = Request(exposer_->port(), "GET", "/metrics");
        if (r.status == 200 && r.body == registry_.Serialize()) ++good;
      }
    });
  }
  for (auto& client : clients) client.join();
  EXPECT_EQ(good.load(), 60);
}

// Idle connections (a TCP connect, no request) each hold a worker until the request
// timeout (2 s): twelve of them, more than the 8 workers, must not keep a scrape waiting
// past a few seconds (with the former 2 workers and 10 s, four blinded every scrape).
TEST_F(HttpExposerTest, ScrapesAreAnsweredWhileIdleConnectionsAreOpen) {
  std::vector<int> idle;
  for (int i = 0; i < 12; ++i) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    ASSERT_GE(fd, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<uint16_t>(exposer_->port()));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
    idle.push_back(fd);
  }
  for (int scrape = 0; scrape < 3; ++scrape) {
    const auto start = std::chrono::steady_clock::now();
    const HttpResponse r = Request(exposer_->port(), "GET", "/metrics");
    const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(r.status, 200);
    EXPECT_LT(waited_s, 4.0) << "scrape " << scrape;
  }
  for (int fd : idle) close(fd);
}

TEST_F(HttpExposerTest, DestructorStopsTheServer) {
  const int port = exposer_->port();
  ASSERT_EQ(Request(port, "GET", "/metrics").status, 200);
  exposer_.reset();
  EXPECT_FALSE(Request(port, "GET", "/metrics").ok);
}

TEST(HttpExposerStart, SecondExposerOnTheSamePortFailsWithAStatus) {
  Registry registry;
  auto first = HttpExposer::Start("127.0.0.1:0", &registry);
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  const std::string address = "127.0.0.1:" + std::to_string((*first)->port());
  auto second = HttpExposer::Start(address, &registry);
  ASSERT_FALSE(second.ok());
  EXPECT_EQ(second.status().code(), StatusCode::kUnavailable);
  EXPECT_NE(second.status().message().find(address), std::string::npos) << second.status().message();
  // civetweb's reason comes along (its log line "cannot bind to <address>: ...").
  EXPECT_NE(second.status().message().find("bind"), std::string::npos) << second.status().message();
  // The first one still serves.
  EXPECT_EQ(Request((*first)->port(), "GET", "/metrics").status, 200);
}

TEST(HttpExposerStart, MalformedAddressesAreInvalidArgument) {
  Registry registry;
  for (const char* listen :
       {"", "9100", "127.0.0.1", "127.0.0.1:", "127.0.0.1:65536", "127.0.0.1:-1", "127.0.0.1:80,81", "127.0.0.1:80s",
        "1.2.3:80", "example.com:80", "[::1:80", "[zz]:80", ":80"}) {
    auto exposer = HttpExposer::Start(listen, &registry);
    ASSERT_FALSE(exposer.ok()) << listen;
    EXPECT_EQ(exposer.status().code(), StatusCode::kInvalidArgument) << listen;
    EXPECT_NE(exposer.status().message().find(std::string("\"") + listen + "\""), std::string::npos)
        << exposer.status().message();
  }
  EXPECT_EQ(HttpExposer::Start("127.0.0.1:0", nullptr).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(HttpExposer::Start("127.0.0.1:0", &registry, 0).status().code(), StatusCode::kInvalidArgument);
}

TEST(HttpExposerStart, AddressThatIsNotLocalIsUnavailable) {
  Registry registry;
  // 192.0.2.1 is TEST-NET-1 (RFC 5737): never assigned to a local interface.
  auto exposer = HttpExposer::Start("192.0.2.1:0", &registry);
  ASSERT_FALSE(exposer.ok());
  EXPECT_EQ(exposer.status().code(), StatusCode::kUnavailable);
  EXPECT_NE(exposer.status().message().find("192.0.2.1:0"), std::string::npos);
}

TEST(HttpExposerStart, LocalhostMeansLoopback) {
  Registry registry;
  auto exposer = HttpExposer::Start("localhost:0", &registry, 1);
  ASSERT_TRUE(exposer.ok()) << exposer.status().ToString();
  EXPECT_EQ(Request((*exposer)->port(), "GET", "/metrics").status, 200);
}

}  // namespace
}  // namespace localizer::server::metrics
