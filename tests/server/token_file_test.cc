// The bearer-token file and its check (server/service/auth.h), and the start-up validation
// of the TLS options, on their own: no server, no PKI. The server-level behaviour (refusals on
// gRPC and HTTP, roles, TLS) is in security_test.cc.
#include <gtest/gtest.h>

#include <string>

#include "server/service/auth.h"
#include "server/service/server_options.h"

namespace localizer::server::testing {
namespace {

TEST(TokenAuthenticatorTest, ParsesRolesSkipsCommentsAndChecksRoles) {
  auto auth = TokenAuthenticator::Parse(
      "# comment\n\n  client   aaaaaaaaaaaaaaaa  \r\noperator\tbbbbbbbbbbbbbbbbbbbb\n   # indented comment\n", "test");
  ASSERT_TRUE(auth.ok()) << auth.status().ToString();
  EXPECT_EQ((*auth)->token_count(), 2u);
  const TokenAuthenticator& a = **auth;
  EXPECT_EQ(a.Check("Bearer aaaaaaaaaaaaaaaa", Role::kClient), AuthDecision::kAllowed);
  EXPECT_EQ(a.Check("bearer aaaaaaaaaaaaaaaa", Role::kClient), AuthDecision::kAllowed);
  EXPECT_EQ(a.Check("Bearer aaaaaaaaaaaaaaaa", Role::kOperator), AuthDecision::kPermissionDenied);
  EXPECT_EQ(a.Check("Bearer bbbbbbbbbbbbbbbbbbbb", Role::kOperator), AuthDecision::kAllowed);
  EXPECT_EQ(a.Check("Bearer bbbbbbbbbbbbbbbbbbbb", Role::kClient), AuthDecision::kAllowed);
  EXPECT_EQ(a.Check("", Role::kClient), AuthDecision::kUnauthenticated);
  EXPECT_EQ(a.Check("Bearer ", Role::kClient), AuthDecision::kUnauthenticated);
  EXPECT_EQ(a.Check("aaaaaaaaaaaaaaaa", Role::kClient), AuthDecision::kUnauthenticated);
  EXPECT_EQ(a.Check("Basic aaaaaaaaaaaaaaaa", Role::kClient), AuthDecision::kUnauthenticated);
  EXPECT_EQ(a.Check("Bearer aaaaaaaaaaaaaaa", Role::kClient), AuthDecision::kUnauthenticated);    // prefix
  EXPECT_EQ(a.Check("Bearer aaaaaaaaaaaaaaaaa", Role::kClient), AuthDecision::kUnauthenticated);  // longer
}

TEST(TokenAuthenticatorTest, RefusalReasonTellsMissingFromInvalidAndForbidden) {
  EXPECT_STREQ(RefusalReason(AuthDecision::kAllowed, "Bearer x"), "");
  EXPECT_STREQ(RefusalReason(AuthDecision::kUnauthenticated, ""), "missing");
  EXPECT_STREQ(RefusalReason(AuthDecision::kUnauthenticated, "Bearer "), "invalid");
  EXPECT_STREQ(RefusalReason(AuthDecision::kUnauthenticated, "Basic abc"), "invalid");
  EXPECT_STREQ(RefusalReason(AuthDecision::kPermissionDenied, "Bearer aaaaaaaaaaaaaaaa"), "forbidden");
}

TEST(TokenAuthenticatorTest, RefusesBadFilesNamingTheLineButNotTheToken) {
  const auto error = [](const std::string& text) {
    auto auth = TokenAuthenticator::Parse(text, "--auth-token-file \"t\"");
    return auth.ok() ? std::string("accepted") : auth.status().message();
  };
  std::string e = error("client short-token-15c\n");
  EXPECT_NE(e.find("line 1"), std::string::npos) << e;
  EXPECT_NE(e.find("at least 16"), std::string::npos) << e;
  EXPECT_EQ(e.find("short-token"), std::string::npos) << e;
  e = error("# x\nadmin cccccccccccccccccccc\n");
  EXPECT_NE(e.find("line 2"), std::string::npos) << e;
  EXPECT_NE(e.find("role"), std::string::npos) << e;
  e = error("client cccccccccccccccccccc\noperator cccccccccccccccccccc\n");
  EXPECT_NE(e.find("listed twice"), std::string::npos) << e;
  e = error("client cccccccccccccccccccc extra\n");
  EXPECT_NE(e.find("3 field(s)"), std::string::npos) << e;
  e = error("cccccccccccccccccccc\n");
  EXPECT_NE(e.find("1 field(s)"), std::string::npos) << e;
  e = error("# only comments\n\n");
  EXPECT_NE(e.find("holds no token"), std::string::npos) << e;
  e =
      error(std::string("client ccccccccccccccc\x01"
                        "ccccc\n"));
  EXPECT_NE(e.find("printable ASCII"), std::string::npos) << e;
  auto missing = TokenAuthenticator::Load("/nonexistent/localizer-tokens");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("--auth-token-file \"/nonexistent/localizer-tokens\""), std::string::npos)
      << missing.status().message();
}

TEST(ServerOptionsSecurityTest, ValidateNamesTheField) {
  ServerOptions o;
  o.tls_key = "k.pem";
  EXPECT_NE(o.Validate().message().find("tls_cert and tls_key"), std::string::npos);
  ServerOptions ca;
  ca.tls_client_ca = "ca.pem";
  EXPECT_NE(ca.Validate().message().find("tls_client_ca needs tls_cert"), std::string::npos);
}

}  // namespace
}  // namespace localizer::server::testing
