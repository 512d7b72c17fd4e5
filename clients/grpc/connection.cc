#include "clients/grpc/connection.h"

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>
#include <grpcpp/support/channel_arguments.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

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

}  // namespace

std::shared_ptr<grpc::Channel> Connect(const std::string& target) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(kMaxMessageBytes);
  args.SetMaxSendMessageSize(kMaxMessageBytes);
  return grpc::CreateCustomChannel(target, grpc::InsecureChannelCredentials(), args);
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
