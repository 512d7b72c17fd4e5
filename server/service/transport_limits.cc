#include "server/service/transport_limits.h"

#include <grpc/grpc.h>
#include <grpcpp/resource_quota.h>
#include <grpcpp/server_builder.h>

#include <algorithm>
#include <cstdint>

namespace localizer::server {
namespace {

int Milliseconds(double s) { return static_cast<int>(std::clamp(s * 1e3, 0.0, 2147483647.0)); }

}  // namespace

void ApplyTransportLimits(const TransportLimits& limits, grpc::ServerBuilder* builder) {
  builder->AddChannelArgument(GRPC_ARG_MAX_CONCURRENT_STREAMS, limits.max_streams_per_connection);
  if (limits.grpc_memory_mib > 0) {
    grpc::ResourceQuota quota("localizer-transport");
    quota.Resize(static_cast<size_t>(limits.grpc_memory_mib) << 20);
    builder->SetResourceQuota(quota);
  }
  if (limits.connection_idle_s > 0.0) {
    builder->AddChannelArgument(GRPC_ARG_MAX_CONNECTION_IDLE_MS, Milliseconds(limits.connection_idle_s));
  }
  if (limits.connection_age_s > 0.0) {
    builder->AddChannelArgument(GRPC_ARG_MAX_CONNECTION_AGE_MS, Milliseconds(limits.connection_age_s));
    builder->AddChannelArgument(GRPC_ARG_MAX_CONNECTION_AGE_GRACE_MS, 30000);
  }
  if (limits.keepalive_s > 0.0) {
    builder->AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, Milliseconds(limits.keepalive_s));
    builder->AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 20000);
  }
  builder->AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 10000);
  builder->AddChannelArgument(GRPC_ARG_HTTP2_MAX_PING_STRIKES, 2);
}

}  // namespace localizer::server
