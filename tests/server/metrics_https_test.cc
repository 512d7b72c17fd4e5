// HTTPS on the server's HTTP side (--metrics-tls-cert, --metrics-tls-key,
// --metrics-tls-client-ca): in process (Server::Start) and as the binary (ready file, exit
// codes, clients hanging up). TlsFront itself is tested in tls_front_test.cc. The clients are
// OpenSSL in C++ (tests/server/https_client.h); the PKI comes from
// deploy/tls/make_test_certs.sh (without the openssl CLI the tests skip with the reason).
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "server/metrics/tls_front.h"
#include "server/service/server.h"
#include "tests/server/http_client.h"
#include "tests/server/https_client.h"
#include "tests/server/run_shell.h"
#include "tests/server/test_pki.h"

extern char** environ;

namespace localizer::server {
namespace {

namespace fs = std::filesystem;
using ::localizer::testing::HttpsRequest;
using ::localizer::testing::HttpsResponse;
using ::localizer::testing::Pki;
using ::localizer::testing::ReadText;
using ::localizer::testing::TlsClientOptions;
using ::localizer::testing::TlsConnection;

constexpr char kClientToken[] = "client-token-0123456789abcdef";
constexpr char kOperatorToken[] = "operator-token-fedcba9876543210";

// The value of `series` ("name{labels}") in a text-format body; -1 when absent.
double SeriesValue(const std::string& body, const std::string& series) {
  const size_t at = body.find("\n" + series + " ");
  return at == std::string::npos ? -1.0 : std::stod(body.substr(at + series.size() + 2));
}

// --- The server with --metrics-tls-* ------------------------------------------------------

class HttpsServerTest : public ::testing::Test {
 protected:
  void TearDown() override {
    if (server_) server_->Shutdown();
  }
  ServerOptions Options() const {
    ServerOptions options;
    options.listen = "127.0.0.1:0";
    options.metrics_listen = "127.0.0.1:0";
    options.workers = 2;
    options.log_level = "error";
    options.metrics_tls_cert = pki_.Cert("server.crt");
    options.metrics_tls_key = pki_.Cert("server.key");
    return options;
  }
  void StartServer(const ServerOptions& options) {
    auto server = Server::Start(options);
    ASSERT_TRUE(server.ok()) << server.status().ToString();
    server_ = std::move(server).value();
  }
  TlsClientOptions Trusting() const {
    TlsClientOptions client;
    client.ca_file = pki_.Cert("ca.crt");
    return client;
  }

  Pki pki_;
  std::unique_ptr<Server> server_;
};

TEST_F(HttpsServerTest, MetricsPortServesHttpsOnly) {
  SKIP_WITHOUT_PKI();
  StartServer(Options());
  const int port = server_->metrics_port();
  HttpsResponse r = HttpsRequest(port, "GET", "/metrics", Trusting());
  ASSERT_EQ(r.status, 200) << r.error;
  EXPECT_NE(r.body.find("localizer_build_info{"), std::string::npos);
  EXPECT_EQ(SeriesValue(r.body, "localizer_http_tls_handshake_failures_total{reason=\"protocol\"}"), 0.0) << r.body;
  EXPECT_FALSE(::localizer::testing::Request(port, "GET", "/metrics").ok);  // plaintext gets nothing
  r = HttpsRequest(port, "GET", "/metrics", Trusting());
  EXPECT_EQ(SeriesValue(r.body, "localizer_http_tls_handshake_failures_total{reason=\"protocol\"}"), 1.0);
  EXPECT_EQ(HttpsRequest(port, "GET", "/", Trusting()).status, 200);  // the live view, no tokens
  EXPECT_EQ(HttpsRequest(port, "GET", "/sessions", Trusting()).status, 200);
}

TEST_F(HttpsServerTest, HandshakeFailuresAreExportedAtZeroWithoutHttps) {
  ServerOptions options = Options();
  options.metrics_tls_cert.clear();
  options.metrics_tls_key.clear();
  StartServer(options);
  const auto r = ::localizer::testing::Request(server_->metrics_port(), "GET", "/metrics");
  ASSERT_EQ(r.status, 200);
  for (const char* reason : metrics::kHandshakeFailureReasons) {
    EXPECT_EQ(
        SeriesValue(r.body, std::string("localizer_http_tls_handshake_failures_total{reason=\"") + reason + "\"}"), 0.0)
        << reason;
  }
}

TEST_F(HttpsServerTest, OperatorTokenStillGuardsSessionsOverHttps) {
  SKIP_WITHOUT_PKI();
  {
    std::ofstream tokens(pki_.Path("tokens"));
    tokens << "client " << kClientToken << "\noperator " << kOperatorToken << "\n";
  }
  ServerOptions options = Options();
  options.auth_token_file = pki_.Path("tokens");
  StartServer(options);
  const int port = server_->metrics_port();
  HttpsResponse r = HttpsRequest(port, "GET", "/sessions", Trusting());
  EXPECT_EQ(r.status, 401) << r.error;
  EXPECT_EQ(r.headers["www-authenticate"].rfind("Bearer", 0), 0u);
  EXPECT_EQ(HttpsRequest(port, "GET", "/sessions", Trusting(), kClientToken).status, 403);
  r = HttpsRequest(port, "GET", "/sessions", Trusting(), kOperatorToken);
  EXPECT_EQ(r.status, 200) << r.error;
  EXPECT_NE(r.body.find("\"sessions\""), std::string::npos);
  EXPECT_EQ(HttpsRequest(port, "GET", "/?token=" + std::string(kOperatorToken), Trusting()).status, 200);
  EXPECT_EQ(HttpsRequest(port, "GET", "/metrics", Trusting()).status, 200);  // open, as over HTTP
}

TEST_F(HttpsServerTest, MutualTlsOnTheHttpSide) {
  SKIP_WITHOUT_PKI();
  ServerOptions options = Options();
  options.metrics_tls_client_ca = pki_.Cert("ca.crt");
  StartServer(options);
  const int port = server_->metrics_port();
  EXPECT_FALSE(HttpsRequest(port, "GET", "/metrics", Trusting()).ok);
  TlsClientOptions with_cert = Trusting();
  with_cert.cert_file = pki_.Cert("client.crt");
  with_cert.key_file = pki_.Cert("client.key");
  const HttpsResponse r = HttpsRequest(port, "GET", "/metrics", with_cert);
  EXPECT_EQ(r.status, 200) << r.error;
  EXPECT_EQ(SeriesValue(r.body, "localizer_http_tls_handshake_failures_total{reason=\"certificate\"}"), 1.0);
}

TEST_F(HttpsServerTest, BadMetricsTlsFilesStopTheStartNamingFlagAndPath) {
  SKIP_WITHOUT_PKI();
  ASSERT_TRUE(pki_.Make("other"));
  std::ofstream(pki_.Path("not.pem")) << "hello\n";
  const auto start_error = [](const ServerOptions& options) {
    auto server = Server::Start(options);
    return server.ok() ? std::string("started") : server.status().ToString();
  };
  ServerOptions o = Options();
  o.metrics_tls_cert = pki_.Path("missing.crt");
  std::string error = start_error(o);
  EXPECT_NE(error.find("INVALID_ARGUMENT"), std::string::npos) << error;
  EXPECT_NE(error.find("--metrics-tls-cert"), std::string::npos) << error;
  EXPECT_NE(error.find(pki_.Path("missing.crt")), std::string::npos) << error;

  o = Options();
  o.metrics_tls_key = pki_.Path("not.pem");
  error = start_error(o);
  EXPECT_NE(error.find("--metrics-tls-key"), std::string::npos) << error;
  EXPECT_NE(error.find("not PEM"), std::string::npos) << error;

  o = Options();
  o.metrics_tls_key = pki_.Cert("server.key", "other");
  error = start_error(o);
  EXPECT_NE(error.find("--metrics-tls-key"), std::string::npos) << error;
  EXPECT_NE(error.find("not the key"), std::string::npos) << error;

  o = Options();
  o.metrics_tls_client_ca = pki_.Path("nowhere/ca.crt");
  error = start_error(o);
  EXPECT_NE(error.find("--metrics-tls-client-ca"), std::string::npos) << error;
  EXPECT_NE(error.find(pki_.Path("nowhere/ca.crt")), std::string::npos) << error;

  o = Options();
  o.metrics_tls_key.clear();
  EXPECT_NE(start_error(o).find("metrics_tls_cert and metrics_tls_key go together"), std::string::npos);
  o = Options();
  o.metrics_listen.clear();
  EXPECT_NE(start_error(o).find("metrics_tls_cert needs metrics_listen"), std::string::npos);
}

// --- The binary --------------------------------------------------------------------------

// localizer-server started with `args`; stopped with SIGTERM by Stop or the destructor.
class ServerProcess {
 public:
  explicit ServerProcess(std::vector<std::string> args) {
    args.insert(args.begin(), LOCALIZER_SERVER_BIN);
    std::vector<char*> argv;
    for (auto& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    if (posix_spawn(&pid_, argv[0], nullptr, nullptr, argv.data(), environ) != 0) pid_ = -1;
  }
  ~ServerProcess() { (void)Stop(); }
  // Sends SIGTERM and returns the exit status (-1 if it did not exit normally).
  int Stop() {
    if (pid_ <= 0) return -1;
    kill(pid_, SIGTERM);
    return Wait();
  }
  int Wait() {
    if (pid_ <= 0) return -1;
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  bool Running() const { return pid_ > 0 && waitpid(pid_, nullptr, WNOHANG) == 0; }

 private:
  pid_t pid_ = -1;
};

TEST_F(HttpsServerTest, BinaryServesHttpsAndReportsThePublicPortInTheReadyFile) {
  SKIP_WITHOUT_PKI();
  const std::string ready = pki_.Path("ready.json");
  ServerProcess server({"--listen", "127.0.0.1:0", "--metrics-listen", "127.0.0.1:0", "--workers", "1", "--log-level",
                        "warn", "--ready-file", ready, "--metrics-tls-cert", pki_.Cert("server.crt"),
                        "--metrics-tls-key", pki_.Cert("server.key")});
  for (int i = 0; i < 300 && !fs::exists(ready); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_TRUE(fs::exists(ready)) << "no ready file";
  const std::string text = ReadText(ready);
  const size_t at = text.find("\"metrics_port\": ");
  ASSERT_NE(at, std::string::npos) << text;
  const int port = std::stoi(text.substr(at + 16));
  EXPECT_EQ(HttpsRequest(port, "GET", "/metrics", Trusting()).status, 200);
  // Clients that hang up in the middle of the live page (about 10 kB), and plaintext sent to
  // the HTTPS port: the server keeps serving.
  for (int i = 0; i < 30; ++i) {
    TlsConnection hang_up(port, Trusting());
    ASSERT_TRUE(hang_up.ok()) << hang_up.error();
    ASSERT_TRUE(hang_up.Send("GET / HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n"));
    if (i % 2 == 1) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // mid-response, some of them
  }  // closed unread: the kernel answers the front's next write with a reset
  for (int i = 0; i < 30; ++i) {
    (void)::localizer::testing::Request(port, "GET", "/");  // plaintext garbage
  }
  const HttpsResponse r = HttpsRequest(port, "GET", "/", Trusting());
  EXPECT_EQ(r.status, 200) << r.error;
  EXPECT_TRUE(server.Running());
  EXPECT_EQ(server.Stop(), 0);
}

TEST_F(HttpsServerTest, BinaryExitsOneOnABadMetricsTlsFile) {
  SKIP_WITHOUT_PKI();
  ASSERT_TRUE(pki_.Make("other"));
  const std::string command = std::string("'") + LOCALIZER_SERVER_BIN +
                              "' --listen 127.0.0.1:0 --metrics-listen 127.0.0.1:0 --metrics-tls-cert '" +
                              pki_.Cert("server.crt") + "' --metrics-tls-key '" + pki_.Cert("server.key", "other") +
                              "' 2>'" + pki_.Path("stderr") + "'";
  const int status = localizer::testing::RunShell(command);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  const std::string err = ReadText(pki_.Path("stderr"));
  EXPECT_NE(err.find("--metrics-tls-key"), std::string::npos) << err;
  EXPECT_NE(err.find(pki_.Cert("server.key", "other")), std::string::npos) << err;
  // A usage error (a cert without its key) is exit 2, as for --tls-cert.
  const std::string half = std::string("'") + LOCALIZER_SERVER_BIN + "' --listen 127.0.0.1:0 --metrics-tls-cert '" +
                           pki_.Cert("server.crt") + "' 2>/dev/null";
  const int half_status = localizer::testing::RunShell(half);
  ASSERT_TRUE(WIFEXITED(half_status));
  EXPECT_EQ(WEXITSTATUS(half_status), 2);
}

}  // namespace
}  // namespace localizer::server
