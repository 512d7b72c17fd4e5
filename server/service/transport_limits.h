// gRPC transport settings that bound what one client can hold: streams per connection, the
// memory gRPC itself may use for buffers, and how idle, dead and old connections end.
//
//   field                        default  meaning
//   max_streams_per_connection   100      concurrent RPCs on one HTTP/2 connection
//   grpc_memory_mib              1024     gRPC's resource quota: its read/write buffers
//                                         shrink under pressure instead of growing past it
//                                         (0: unlimited)
//   connection_idle_s            600      a connection with no RPC this long gets GOAWAY
//                                         (clients reconnect transparently); 0: never
//   connection_age_s             0        GOAWAY after this long, streams included (they end
//                                         after a 30 s grace; resume continues them); 0: never
//                                         -- sessions stream for hours, so off by default
//   keepalive_s                  60       the server pings a connection this quiet and drops
//                                         it after 20 s without an answer (a client that
//                                         vanished without a FIN detaches its session)
// Keepalive enforcement: a client may ping at most every 10 s without data; the second ping
// too early closes its connection.
#pragma once

namespace grpc {
class ServerBuilder;
}  // namespace grpc

namespace localizer::server {

struct TransportLimits {
  int max_streams_per_connection = 100;
  int grpc_memory_mib = 1024;
  double connection_idle_s = 600.0;
  double connection_age_s = 0.0;
  double keepalive_s = 60.0;
};

void ApplyTransportLimits(const TransportLimits& limits, grpc::ServerBuilder* builder);

}  // namespace localizer::server
