// Transport security and authentication (docs/SECURITY.md): TLS and mutual TLS on gRPC,
// bearer tokens with roles on gRPC and on the HTTP pages, clear start-up errors for bad
// files. The PKI is made at test time by deploy/tls/make_test_certs.sh (the openssl CLI) in
// a temporary directory; without openssl the TLS tests skip with the reason. The token file's
// parser and the options check on their own: token_file_test.cc.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "clients/grpc/connection.h"
#include "server/service/auth.h"
#include "server/service/tls_credentials.h"
#include "tests/server/http_client.h"
#include "tests/server/run_shell.h"
#include "tests/server/service_fixture.h"

namespace localizer::server::testing {
namespace {

namespace fs = std::filesystem;

constexpr char kClientToken[] = "client-token-0123456789abcdef";
constexpr char kOperatorToken[] = "operator-token-fedcba9876543210";

void WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

bool HaveOpenssl() { return localizer::testing::RunShell("openssl version >/dev/null 2>&1") == 0; }

// A temporary directory with the test PKI and token files; removed at the end.
class Pki {
 public:
  Pki() {
    char pattern[] = "/tmp/localizer-tls-XXXXXX";
    dir_ = mkdtemp(pattern);
    WriteFile(dir_ / "tokens", std::string("# test tokens\n\nclient ") + kClientToken +
                                   "\n   \n# operator\noperator\t" + kOperatorToken + "\n");
    WriteFile(dir_ / "client.token", std::string(kClientToken) + "\n");
    WriteFile(dir_ / "operator.token", std::string("# the operator's\noperator ") + kOperatorToken + "\n");
    WriteFile(dir_ / "wrong.token", "not-a-known-token-000000000000\n");
  }
  ~Pki() {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  // Runs make_test_certs.sh into dir()/name; false when it failed.
  bool MakeCertificates(const std::string& name = "pki") {
    const std::string command = "bash '" LOCALIZER_SOURCE_DIR "/deploy/tls/make_test_certs.sh' '" +
                                (dir_ / name).string() + "' >/dev/null 2>&1";
    return localizer::testing::RunShell(command) == 0;
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string Cert(const std::string& file, const std::string& pki = "pki") const { return Path(pki + "/" + file); }

 private:
  fs::path dir_;
};

class SecurityTest : public ::testing::Test {
 protected:
  void SetUp() override { scenario_ = std::make_unique<Scenario>(MakeScenario("tetra-water", 1.0, 7, kBlock, 256)); }
  void TearDown() override {
    if (server_) server_->Shutdown();
  }
  void StartServer(ServerOptions options) {
    options.listen = "127.0.0.1:0";
    options.metrics_listen = "127.0.0.1:0";
    options.workers = 2;
    options.log_level = "error";
    auto server = Server::Start(options);
    ASSERT_TRUE(server.ok()) << server.status().ToString();
    server_ = std::move(server).value();
  }
  std::string Target() const { return "127.0.0.1:" + std::to_string(server_->grpc_port()); }
  std::unique_ptr<v1::Localizer::Stub> Stub(const client::ConnectOptions& options) {
    auto channel = client::Connect(Target(), options);
    EXPECT_TRUE(channel.ok()) << channel.status().ToString();
    return channel.ok() ? v1::Localizer::NewStub(*channel) : nullptr;
  }
  static grpc::Status ListSessions(v1::Localizer::Stub* stub, double timeout_s = 10.0) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(int(timeout_s * 1000)));
    v1::ListSessionsResponse response;
    return stub->ListSessions(&context, v1::ListSessionsRequest(), &response);
  }
  // Opens a session, streams the scenario's first blocks, half-closes; returns the status
  // and sets *estimates.
  grpc::Status Stream(v1::Localizer::Stub* stub, size_t* estimates) {
    TestStream stream(stub);
    stream.Send(scenario_->OpenRequest());
    const int64_t blocks = std::min<int64_t>(4, scenario_->BlockCount(kBlock));
    for (int64_t k = 1; k <= blocks; ++k) stream.Send(scenario_->BlockRequest(k, kBlock));
    grpc::Status status = stream.Close();  // not const: returned by move
    *estimates = stream.estimates().size();
    return status;
  }

  static constexpr int64_t kBlock = 4096;
  std::unique_ptr<Scenario> scenario_;
  std::unique_ptr<Server> server_;
  Pki pki_;
};

#define SKIP_WITHOUT_OPENSSL()                                                     \
  if (!HaveOpenssl())                                                              \
    GTEST_SKIP() << "the openssl CLI is not installed (Debian: openssl): no test " \
                    "certificates";                                                \
  ASSERT_TRUE(pki_.MakeCertificates()) << "deploy/tls/make_test_certs.sh failed"

// --- TLS and mutual TLS --------------------------------------------------------------------

TEST_F(SecurityTest, TlsClientConnectsAndStreams) {
  SKIP_WITHOUT_OPENSSL();
  ServerOptions options;
  options.tls_cert = pki_.Cert("server.crt");
  options.tls_key = pki_.Cert("server.key");
  StartServer(options);
  client::ConnectOptions tls;
  tls.tls_ca = pki_.Cert("ca.crt");
  auto stub = Stub(tls);
  size_t estimates = 0;
  const grpc::Status status = Stream(stub.get(), &estimates);
  EXPECT_TRUE(status.ok()) << status.error_message();
  EXPECT_GT(estimates, 0u);
}

TEST_F(SecurityTest, PlaintextClientToTlsServerFails) {
  SKIP_WITHOUT_OPENSSL();
  ServerOptions options;
  options.tls_cert = pki_.Cert("server.crt");
  options.tls_key = pki_.Cert("server.key");
  StartServer(options);
  auto plain = v1::Localizer::NewStub(client::Connect(Target()));
  const grpc::Status status = ListSessions(plain.get(), 3.0);
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
}

TEST_F(SecurityTest, TlsClientRefusesServerSignedByAnotherCa) {
  SKIP_WITHOUT_OPENSSL();
  ASSERT_TRUE(pki_.MakeCertificates("other"));
  ServerOptions options;
  options.tls_cert = pki_.Cert("server.crt");
  options.tls_key = pki_.Cert("server.key");
  StartServer(options);
  client::ConnectOptions tls;
  tls.tls_ca = pki_.Cert("ca.crt", "other");
  const grpc::Status status = ListSessions(Stub(tls).get(), 3.0);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
}

TEST_F(SecurityTest, MutualTlsRefusesClientWithoutCertificateAndAcceptsOneWith) {
  SKIP_WITHOUT_OPENSSL();
  ASSERT_TRUE(pki_.MakeCertificates("other"));
  ServerOptions options;
  options.tls_cert = pki_.Cert("server.crt");
  options.tls_key = pki_.Cert("server.key");
  options.tls_client_ca = pki_.Cert("ca.crt");
  StartServer(options);

  client::ConnectOptions no_cert;
  no_cert.tls_ca = pki_.Cert("ca.crt");
  EXPECT_EQ(ListSessions(Stub(no_cert).get(), 3.0).error_code(), grpc::StatusCode::UNAVAILABLE);

  client::ConnectOptions foreign = no_cert;  // a certificate from a CA the server does not trust
  foreign.tls_cert = pki_.Cert("client.crt", "other");
  foreign.tls_key = pki_.Cert("client.key", "other");
  EXPECT_EQ(ListSessions(Stub(foreign).get(), 3.0).error_code(), grpc::StatusCode::UNAVAILABLE);

  client::ConnectOptions with_cert = no_cert;
  with_cert.tls_cert = pki_.Cert("client.crt");
  with_cert.tls_key = pki_.Cert("client.key");
  auto stub = Stub(with_cert);
  EXPECT_TRUE(ListSessions(stub.get()).ok());
  size_t estimates = 0;
  EXPECT_TRUE(Stream(stub.get(), &estimates).ok());
  EXPECT_GT(estimates, 0u);
}

TEST_F(SecurityTest, BadTlsFilesStopTheStartNamingFlagAndPath) {
  SKIP_WITHOUT_OPENSSL();
  ASSERT_TRUE(pki_.MakeCertificates("other"));
  const auto start_error = [](const ServerOptions& o) {
    ServerOptions options = o;
    options.listen = "127.0.0.1:0";
    options.metrics_listen = "";
    auto server = Server::Start(options);
    return server.ok() ? std::string("started") : server.status().ToString();
  };
  ServerOptions o;
  o.tls_cert = pki_.Path("missing.crt");
  o.tls_key = pki_.Cert("server.key");
  std::string error = start_error(o);
  EXPECT_NE(error.find("INVALID_ARGUMENT"), std::string::npos) << error;
  EXPECT_NE(error.find("--tls-cert"), std::string::npos) << error;
  EXPECT_NE(error.find(pki_.Path("missing.crt")), std::string::npos) << error;

  o.tls_cert = pki_.Path("tokens");  // not PEM
  error = start_error(o);
  EXPECT_NE(error.find("--tls-cert"), std::string::npos) << error;
  EXPECT_NE(error.find("not PEM"), std::string::npos) << error;

  o.tls_cert = pki_.Cert("server.crt");
  o.tls_key = pki_.Cert("server.key", "other");  // another key
  error = start_error(o);
  EXPECT_NE(error.find("--tls-key"), std::string::npos) << error;
  EXPECT_NE(error.find("not the key"), std::string::npos) << error;

  o.tls_key = pki_.Cert("server.key");
  o.tls_client_ca = pki_.Path("nowhere/ca.crt");
  error = start_error(o);
  EXPECT_NE(error.find("--tls-client-ca"), std::string::npos) << error;

  ServerOptions half;
  half.tls_cert = pki_.Cert("server.crt");
  error = start_error(half);
  EXPECT_NE(error.find("tls_cert and tls_key go together"), std::string::npos) << error;
}

TEST_F(SecurityTest, ServerBinaryExitsOneOnAnUnreadableFile) {
  const std::string command = std::string("'") + LOCALIZER_SERVER_BIN +
                              "' --listen 127.0.0.1:0 --metrics-listen '' --auth-token-file '" + pki_.Path("absent") +
                              "' 2>" + pki_.Path("stderr");
  const int status = localizer::testing::RunShell(command);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  std::ifstream in(pki_.Path("stderr"));
  const std::string err((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(err.find("--auth-token-file"), std::string::npos) << err;
  EXPECT_NE(err.find(pki_.Path("absent")), std::string::npos) << err;
}

// --- Tokens and roles -------------------------------------------------------------------------

class TokenTest : public SecurityTest {
 protected:
  void SetUp() override {
    SecurityTest::SetUp();
    ServerOptions options;
    options.auth_token_file = pki_.Path("tokens");
    StartServer(options);
  }
  std::unique_ptr<v1::Localizer::Stub> StubWithToken(const std::string& token_file) {
    client::ConnectOptions options;
    options.auth_token_file = token_file.empty() ? "" : pki_.Path(token_file);
    return Stub(options);
  }
};

TEST_F(TokenTest, NoTokenIsUnauthenticatedOnEveryMethod) {
  auto stub = StubWithToken("");
  size_t estimates = 0;
  const grpc::Status track = Stream(stub.get(), &estimates);
  EXPECT_EQ(track.error_code(), grpc::StatusCode::UNAUTHENTICATED) << track.error_message();
  EXPECT_EQ(estimates, 0u);
  EXPECT_EQ(ListSessions(stub.get()).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  grpc::ClientContext locate_context;
  v1::LocateResponse located;
  EXPECT_EQ(stub->Locate(&locate_context, v1::LocateRequest(), &located).error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
  grpc::ClientContext close_context;
  v1::CloseSessionResponse closed;
  EXPECT_EQ(stub->CloseSession(&close_context, v1::CloseSessionRequest(), &closed).error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
}

TEST_F(TokenTest, WrongTokenIsUnauthenticatedAndNotEchoed) {
  auto stub = StubWithToken("wrong.token");
  const grpc::Status status = ListSessions(stub.get());
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED) << status.error_message();
  EXPECT_EQ(status.error_message().find("not-a-known-token"), std::string::npos) << status.error_message();
  size_t estimates = 0;
  EXPECT_EQ(Stream(stub.get(), &estimates).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  // A known token under another scheme is refused too.
  auto plain = StubWithToken("");
  grpc::ClientContext context;
  context.AddMetadata("authorization", std::string("Basic ") + kOperatorToken);
  v1::ListSessionsResponse response;
  EXPECT_EQ(plain->ListSessions(&context, v1::ListSessionsRequest(), &response).error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
}

TEST_F(TokenTest, ClientTokenStreamsButMayNotListOrCloseSessions) {
  auto stub = StubWithToken("client.token");
  size_t estimates = 0;
  const grpc::Status track = Stream(stub.get(), &estimates);
  EXPECT_TRUE(track.ok()) << track.error_message();
  EXPECT_GT(estimates, 0u);
  const grpc::Status list = ListSessions(stub.get());
  EXPECT_EQ(list.error_code(), grpc::StatusCode::PERMISSION_DENIED) << list.error_message();
  grpc::ClientContext close_context;
  v1::CloseSessionResponse closed;
  EXPECT_EQ(stub->CloseSession(&close_context, v1::CloseSessionRequest(), &closed).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
}

TEST_F(TokenTest, OperatorTokenDoesEverything) {
  auto stub = StubWithToken("operator.token");
  TestStream open(stub.get());  // a session left open, to be listed and closed
  ASSERT_TRUE(open.Send(scenario_->OpenRequest()));
  ASSERT_TRUE(open.WaitFor([](const auto& r) { return !r.empty(); }));
  const v1::SessionOpened opened = open.opened();
  ASSERT_FALSE(opened.session_id().empty());

  grpc::ClientContext list_context;
  v1::ListSessionsResponse listed;
  ASSERT_TRUE(stub->ListSessions(&list_context, v1::ListSessionsRequest(), &listed).ok());
  ASSERT_EQ(listed.sessions_size(), 1);
  EXPECT_EQ(listed.sessions(0).session_id(), opened.session_id());

  grpc::ClientContext close_context;
  v1::CloseSessionRequest close;
  close.set_session_id(opened.session_id());
  close.set_resume_token(opened.resume_token());
  v1::CloseSessionResponse closed;
  const grpc::Status status = stub->CloseSession(&close_context, close, &closed);
  EXPECT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(open.Finish().error_code(), grpc::StatusCode::CANCELLED);
}

TEST_F(TokenTest, HttpSessionsAndLivePageNeedTheOperatorToken) {
  using localizer::testing::RawRequest;
  const int port = server_->metrics_port();
  const auto get = [port](const std::string& path, const std::string& token) {
    std::string request = "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n";
    if (!token.empty()) request += "Authorization: Bearer " + token + "\r\n";
    return RawRequest(port, request + "\r\n");
  };
  auto r = get("/sessions", "");
  EXPECT_EQ(r.status, 401);
  EXPECT_EQ(r.headers["www-authenticate"].rfind("Bearer", 0), 0u) << r.headers["www-authenticate"];
  EXPECT_EQ(get("/sessions", "not-a-known-token-000000000000").status, 401);
  EXPECT_EQ(get("/sessions", kClientToken).status, 403);
  r = get("/sessions", kOperatorToken);
  EXPECT_EQ(r.status, 200);
  EXPECT_NE(r.body.find("\"sessions\""), std::string::npos);
  EXPECT_EQ(get("/sessions?token=" + std::string(kOperatorToken), "").status, 401);  // header only
  EXPECT_EQ(get("/", "").status, 401);
  EXPECT_EQ(get("/?token=" + std::string(kClientToken), "").status, 403);
  r = get("/?token=" + std::string(kOperatorToken), "");
  EXPECT_EQ(r.status, 200);
  EXPECT_NE(r.body.find("Authorization"), std::string::npos);  // the page forwards its token
  EXPECT_EQ(get("/", kOperatorToken).status, 200);
  EXPECT_EQ(get("/metrics", "").status, 200);  // aggregate counters stay open
}

// localizer_auth_refusals_total{reason} from a /metrics scrape (-1 when the series is absent).
double AuthRefusals(int metrics_port, const std::string& reason) {
  const std::string series = "\nlocalizer_auth_refusals_total{reason=\"" + reason + "\"} ";
  const auto response = localizer::testing::Request(metrics_port, "GET", "/metrics");
  const size_t at = response.body.find(series);
  return at == std::string::npos ? -1.0 : std::stod(response.body.substr(at + series.size()));
}

TEST_F(TokenTest, RefusalsAreCountedByReasonOnGrpcAndHttp) {
  const int port = server_->metrics_port();
  const auto count = [port] {
    return std::vector<double>{AuthRefusals(port, "missing"), AuthRefusals(port, "invalid"),
                               AuthRefusals(port, "forbidden")};
  };
  EXPECT_EQ(count(), (std::vector<double>{0, 0, 0}));  // exported at 0 before any refusal

  // gRPC: no token, an unknown token, a token under another scheme, a client token on an
  // operator call; an allowed call counts nothing.
  EXPECT_EQ(ListSessions(StubWithToken("").get()).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(count(), (std::vector<double>{1, 0, 0}));
  EXPECT_EQ(ListSessions(StubWithToken("wrong.token").get()).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  auto plain = StubWithToken("");
  grpc::ClientContext context;
  context.AddMetadata("authorization", std::string("Basic ") + kOperatorToken);
  v1::ListSessionsResponse listed;
  EXPECT_EQ(plain->ListSessions(&context, v1::ListSessionsRequest(), &listed).error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(count(), (std::vector<double>{1, 2, 0}));
  EXPECT_EQ(ListSessions(StubWithToken("client.token").get()).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(count(), (std::vector<double>{1, 2, 1}));
  EXPECT_TRUE(ListSessions(StubWithToken("operator.token").get()).ok());
  size_t estimates = 0;
  EXPECT_EQ(Stream(StubWithToken("").get(), &estimates).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(count(), (std::vector<double>{2, 2, 1}));

  // HTTP: the operator pages count alike; /metrics is open and counts nothing.
  using localizer::testing::RawRequest;
  const auto get = [port](const std::string& path, const std::string& token) {
    std::string request = "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n";
    if (!token.empty()) request += "Authorization: Bearer " + token + "\r\n";
    return RawRequest(port, request + "\r\n").status;
  };
  EXPECT_EQ(get("/sessions", ""), 401);
  EXPECT_EQ(get("/", ""), 401);
  EXPECT_EQ(count(), (std::vector<double>{4, 2, 1}));
  EXPECT_EQ(get("/sessions", "not-a-known-token-000000000000"), 401);
  EXPECT_EQ(get("/?token=not-a-known-token-000000000000", ""), 401);
  EXPECT_EQ(count(), (std::vector<double>{4, 4, 1}));
  EXPECT_EQ(get("/sessions", kClientToken), 403);
  EXPECT_EQ(get("/?token=" + std::string(kClientToken), ""), 403);
  EXPECT_EQ(count(), (std::vector<double>{4, 4, 3}));
  EXPECT_EQ(get("/sessions", kOperatorToken), 200);
  EXPECT_EQ(get("/?token=" + std::string(kOperatorToken), ""), 200);
  EXPECT_EQ(count(), (std::vector<double>{4, 4, 3}));
}

TEST_F(SecurityTest, AuthRefusalsAreZeroWithoutTokens) {
  StartServer(ServerOptions());
  size_t estimates = 0;
  EXPECT_TRUE(Stream(Stub(client::ConnectOptions()).get(), &estimates).ok());
  for (const char* reason : {"missing", "invalid", "forbidden"}) {
    EXPECT_EQ(AuthRefusals(server_->metrics_port(), reason), 0.0) << reason;
  }
}

TEST_F(SecurityTest, TokensOverTlsWithClientCertificates) {
  SKIP_WITHOUT_OPENSSL();
  ServerOptions options;
  options.tls_cert = pki_.Cert("server.crt");
  options.tls_key = pki_.Cert("server.key");
  options.tls_client_ca = pki_.Cert("ca.crt");
  options.auth_token_file = pki_.Cert("tokens");  // the script's tokens
  StartServer(options);
  client::ConnectOptions connect;
  connect.tls_ca = pki_.Cert("ca.crt");
  connect.tls_cert = pki_.Cert("client.crt");
  connect.tls_key = pki_.Cert("client.key");
  EXPECT_EQ(ListSessions(Stub(connect).get()).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  connect.auth_token_file = pki_.Cert("client.token");
  EXPECT_EQ(ListSessions(Stub(connect).get()).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  connect.auth_token_file = pki_.Cert("tokens");  // "ROLE TOKEN" lines: the first line's token
  EXPECT_EQ(ListSessions(Stub(connect).get()).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  connect.auth_token_file = pki_.Cert("operator.token");
  EXPECT_TRUE(ListSessions(Stub(connect).get()).ok());
}

TEST_F(SecurityTest, CliTakesTheCredentialFlags) {
  SKIP_WITHOUT_OPENSSL();
  ServerOptions options;
  options.tls_cert = pki_.Cert("server.crt");
  options.tls_key = pki_.Cert("server.key");
  options.auth_token_file = pki_.Cert("tokens");
  StartServer(options);
  const auto run = [&](const std::string& flags) {
    const std::string command = std::string("'") + LOCALIZER_CLI_BIN + "' list --server " + Target() + " " + flags +
                                " >" + pki_.Path("out") + " 2>&1";
    const int status = localizer::testing::RunShell(command);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  EXPECT_EQ(run("--tls-ca " + pki_.Cert("ca.crt") + " --auth-token-file " + pki_.Cert("operator.token")), 0);
  EXPECT_EQ(run("--tls-ca " + pki_.Cert("ca.crt") + " --auth-token-file " + pki_.Cert("client.token")), 1);
  EXPECT_EQ(run("--tls-ca " + pki_.Cert("ca.crt")), 1);
  EXPECT_EQ(run("--tls-ca " + pki_.Path("absent.crt")), 1);
  std::ifstream in(pki_.Path("out"));
  const std::string out((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(out.find("--tls-ca"), std::string::npos) << out;
}

}  // namespace
}  // namespace localizer::server::testing
