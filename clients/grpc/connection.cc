#include "clients/grpc/connection.h"

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>
#include <grpcpp/support/channel_arguments.h>
#include <grpcpp/support/client_interceptor.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <system_error>
#include <vector>

namespace localizer::client {

namespace {

const char* StateName(grpc_connectivity_state state) {
  switch (state) {
    case GRPC_CHANNEL_IDLE:
      return "IDLE";
    case GRPC_CHANNEL_CONNECTING:
      return "CONNECTING";
    case GRPC_CHANNEL_READY:
      return "READY";
    case GRPC_CHANNEL_TRANSIENT_FAILURE:
      return "TRANSIENT_FAILURE";
    case GRPC_CHANNEL_SHUTDOWN:
      return "SHUTDOWN";
  }
  return "UNKNOWN";
}

StatusOr<std::string> ReadFile(const std::string& flag, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    return InvalidArgument("cannot read " + flag + " file \"" + path + "\": " + std::generic_category().message(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return InvalidArgument("cannot read " + flag + " file \"" + path + "\": read error");
  return text.str();
}

StatusOr<std::string> ReadPem(const std::string& flag, const std::string& path) {
  auto text = ReadFile(flag, path);
  if (!text.ok()) return text.status();
  if (text->find("-----BEGIN ") == std::string::npos) {
    return InvalidArgument(flag + " file \"" + path + "\" is not PEM (no '-----BEGIN' line)");
  }
  return text;
}

// Adds "authorization: Bearer TOKEN" to every call's initial metadata. An interceptor, not
// call credentials: gRPC 1.51 cannot compose call credentials with insecure channel
// credentials (the call fails INVALID_ARGUMENT), and the token must also pass over plaintext.
class BearerTokenInterceptor final : public grpc::experimental::Interceptor {
 public:
  explicit BearerTokenInterceptor(std::shared_ptr<const std::string> value) : value_(std::move(value)) {}
  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(grpc::experimental::InterceptionHookPoints::PRE_SEND_INITIAL_METADATA)) {
      methods->GetSendInitialMetadata()->insert({"authorization", *value_});
    }
    methods->Proceed();
  }

 private:
  const std::shared_ptr<const std::string> value_;
};

class BearerTokenFactory final : public grpc::experimental::ClientInterceptorFactoryInterface {
 public:
  explicit BearerTokenFactory(const std::string& token)
      : value_(std::make_shared<const std::string>("Bearer " + token)) {}
  grpc::experimental::Interceptor* CreateClientInterceptor(grpc::experimental::ClientRpcInfo*) override {
    return new BearerTokenInterceptor(value_);
  }

 private:
  const std::shared_ptr<const std::string> value_;
};

grpc::ChannelArguments MessageSizeArgs(bool own_connection = false) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(kMaxMessageBytes);
  args.SetMaxSendMessageSize(kMaxMessageBytes);
  if (own_connection) args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
  return args;
}

}  // namespace

std::shared_ptr<grpc::Channel> Connect(const std::string& target) {
  return grpc::CreateCustomChannel(target, grpc::InsecureChannelCredentials(), MessageSizeArgs());
}

StatusOr<std::string> ReadTokenFile(const std::string& path) {
  auto text = ReadFile("--auth-token-file", path);
  if (!text.ok()) return text.status();
  std::istringstream lines(*text);
  std::string line;
  while (std::getline(lines, line)) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    std::string field, last;
    while (fields >> field) last = field;
    return last;
  }
  return InvalidArgument("--auth-token-file \"" + path + "\" holds no token");
}

StatusOr<std::shared_ptr<grpc::Channel>> Connect(const std::string& target, const ConnectOptions& options) {
  if (options.tls_cert.empty() != options.tls_key.empty()) {
    return InvalidArgument("--tls-cert and --tls-key go together (both or neither)");
  }
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (options.tls()) {
    grpc::SslCredentialsOptions ssl;
    if (!options.tls_ca.empty()) {
      auto ca = ReadPem("--tls-ca", options.tls_ca);
      if (!ca.ok()) return ca.status();
      ssl.pem_root_certs = *ca;
    }
    if (!options.tls_cert.empty()) {
      auto cert = ReadPem("--tls-cert", options.tls_cert);
      if (!cert.ok()) return cert.status();
      auto key = ReadPem("--tls-key", options.tls_key);
      if (!key.ok()) return key.status();
      ssl.pem_cert_chain = *cert;
      ssl.pem_private_key = *key;
    }
    credentials = grpc::SslCredentials(ssl);
  }
  if (options.auth_token_file.empty()) {
    return grpc::CreateCustomChannel(target, credentials, MessageSizeArgs(options.own_connection));
  }
  auto token = ReadTokenFile(options.auth_token_file);
  if (!token.ok()) return token.status();
  std::vector<std::unique_ptr<grpc::experimental::ClientInterceptorFactoryInterface>> interceptors;
  interceptors.push_back(std::make_unique<BearerTokenFactory>(*token));
  return grpc::experimental::CreateCustomChannelWithInterceptors(
      target, credentials, MessageSizeArgs(options.own_connection), std::move(interceptors));
}

grpc::Status FromProxyReset(const grpc::Status& status) {
  if (status.error_code() != grpc::StatusCode::INTERNAL ||
      status.error_message().find("RST_STREAM with error code 2") == std::string::npos) {
    return status;
  }
  return grpc::Status(grpc::StatusCode::UNAVAILABLE,
                      "the server instance behind the proxy is gone (the proxy reset the "
                      "stream: " +
                          status.error_message() + ")");
}

Status WaitConnected(const std::shared_ptr<grpc::Channel>& channel, double timeout_s) {
  if (!(timeout_s >= 0.0) || !std::isfinite(timeout_s)) {
    return InvalidArgument("connect timeout must be finite and >= 0 s, got " + std::to_string(timeout_s));
  }
  const auto deadline =
      std::chrono::system_clock::now() +
      std::chrono::duration_cast<std::chrono::system_clock::duration>(std::chrono::duration<double>(timeout_s));
  grpc_connectivity_state state = channel->GetState(/*try_to_connect=*/true);
  while (state != GRPC_CHANNEL_READY) {
    if (!channel->WaitForStateChange(state, deadline)) break;  // deadline passed
    state = channel->GetState(/*try_to_connect=*/true);
  }
  if (state == GRPC_CHANNEL_READY) return Status::Ok();
  char seconds[32];
  std::snprintf(seconds, sizeof(seconds), "%g", timeout_s);
  return Unavailable(std::string("UNAVAILABLE: not connected after ") + seconds + " s (state " + StateName(state) +
                     ")");
}

void SetSessionKey(grpc::ClientContext* context, const std::string& session_key) {
  if (!session_key.empty()) context->AddMetadata(kSessionKeyMetadata, session_key);
}

std::string RandomSessionKey() {
  std::random_device entropy;
  const uint64_t value = (static_cast<uint64_t>(entropy()) << 32) ^ entropy();
  char text[24];
  std::snprintf(text, sizeof(text), "cli-%016llx", static_cast<unsigned long long>(value));
  return text;
}

}  // namespace localizer::client
