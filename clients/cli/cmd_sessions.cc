// localizer-cli list / close: the sessions a server holds.
#include <chrono>
#include <cstdio>

#include "clients/cli/commands.h"
#include "clients/cli/server_flags.h"
#include "clients/grpc/connection.h"
#include "localizer/v1/localizer.grpc.pb.h"
#include "wire/status_wire.h"

namespace localizer::cli {

namespace {

void SetDeadline(grpc::ClientContext* context, double timeout_s) {
  context->set_deadline(
      std::chrono::system_clock::now() +
      std::chrono::duration_cast<std::chrono::system_clock::duration>(std::chrono::duration<double>(timeout_s)));
}

void PrintSession(const v1::SessionInfo& s) {
  std::string last_sequence = s.has_last_sequence() ? std::to_string(s.last_sequence()) : "-";
  std::printf(
      "session=%s label=\"%s\" backend=%s attached=%d channels=%u sample_rate_hz=%g "
      "blocks=%llu frames=%llu rejections=%llu last_sequence=%s queued=%u age_s=%.1f "
      "idle_s=%.1f expires_in_s=%.1f\n",
      s.session_id().c_str(), s.label().c_str(), s.backend().c_str(), s.attached() ? 1 : 0, s.channel_count(),
      s.sample_rate_hz(), static_cast<unsigned long long>(s.blocks_processed()),
      static_cast<unsigned long long>(s.frames_processed()), static_cast<unsigned long long>(s.rejections()),
      last_sequence.c_str(), s.queued_blocks(), s.age_s(), s.idle_s(), s.expires_in_s());
}

}  // namespace

int RunList(const std::vector<std::string>& args) {
  const std::string command = "list";
  std::string server;
  client::ConnectOptions connect;
  double timeout_s = 10.0;
  FlagSet flags("localizer-cli list --server HOST:PORT",
                "Lists the sessions the server holds, attached or detached, one line each:\n"
                "id, label, backend, whether a stream is attached, blocks and frames processed,\n"
                "rejections, queued blocks, age, idle time and (detached) time left to resume.");
  RegisterServerFlag(flags, &server, /*required=*/true, &connect);
  flags.Double("timeout", &timeout_s, "S", "s", "deadline of the call");
  if (auto exit_code = ParseFlagsOrExit(command, flags, args)) return *exit_code;
  if (!(timeout_s > 0.0)) return UsageError(command, "--timeout must be > 0");
  auto channel = client::Connect(server, connect);
  if (!channel.ok()) return RuntimeError(command, channel.status());
  auto stub = v1::Localizer::NewStub(*channel);
  grpc::ClientContext context;
  SetDeadline(&context, timeout_s);
  v1::ListSessionsResponse response;
  const grpc::Status status = stub->ListSessions(&context, v1::ListSessionsRequest(), &response);
  if (!status.ok()) return RuntimeError(command, wire::FromGrpcStatus(status));
  for (const v1::SessionInfo& s : response.sessions()) PrintSession(s);
  std::printf("sessions=%d\n", response.sessions_size());
  return kExitOk;
}

int RunClose(const std::vector<std::string>& args) {
  const std::string command = "close";
  std::string server;
  client::ConnectOptions connect;
  std::string session_id;
  std::string token;
  std::string session_key;
  double timeout_s = 10.0;
  FlagSet flags("localizer-cli close --server HOST:PORT --session ID --token T",
                "Ends a session now, attached or not (its stream, if any, ends with CANCELLED).\n"
                "The resume token is the one SessionOpened carried (printed by track/simulate\n"
                "--server as the session line).");
  RegisterServerFlag(flags, &server, /*required=*/true, &connect);
  flags.String("session", &session_id, "ID", "session id").Required();
  flags.String("token", &token, "T", "the session's resume token").Required();
  flags.String("session-key", &session_key, "KEY",
               "x-localizer-session-key the session was opened with (for session-affine "
               "proxies)");
  flags.Double("timeout", &timeout_s, "S", "s", "deadline of the call");
  if (auto exit_code = ParseFlagsOrExit(command, flags, args)) return *exit_code;
  if (!(timeout_s > 0.0)) return UsageError(command, "--timeout must be > 0");
  auto channel = client::Connect(server, connect);
  if (!channel.ok()) return RuntimeError(command, channel.status());
  auto stub = v1::Localizer::NewStub(*channel);
  grpc::ClientContext context;
  SetDeadline(&context, timeout_s);
  client::SetSessionKey(&context, session_key);
  v1::CloseSessionRequest request;
  request.set_session_id(session_id);
  request.set_resume_token(token);
  v1::CloseSessionResponse response;
  const grpc::Status status = stub->CloseSession(&context, request, &response);
  if (!status.ok()) return RuntimeError(command, wire::FromGrpcStatus(status));
  std::printf("closed session=%s frames_processed=%llu\n", session_id.c_str(),
              static_cast<unsigned long long>(response.frames_processed()));
  return kExitOk;
}

}  // namespace localizer::cli
