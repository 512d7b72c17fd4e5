// Pieces of the C++ client library that need no server: status mapping, latency
// percentiles, cutting channel-major audio into blocks.
#include <gtest/gtest.h>

#include <vector>

#include "clients/grpc/connection.h"
#include "clients/grpc/latency_summary.h"
#include "clients/grpc/streamer.h"
#include "wire/status_wire.h"

namespace localizer::client {
namespace {

TEST(StatusWire, FromGrpcStatusPrefixesTheCodeName) {
  const Status s = wire::FromGrpcStatus(grpc::Status(grpc::StatusCode::NOT_FOUND, "no session x"));
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_EQ(s.message(), "NOT_FOUND: no session x");
  EXPECT_TRUE(wire::FromGrpcStatus(grpc::Status::OK).ok());
  const Status deadline = wire::FromGrpcStatus(grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, "late"));
  EXPECT_EQ(deadline.code(), StatusCode::kUnavailable);
  EXPECT_EQ(deadline.message(), "DEADLINE_EXCEEDED: late");
  // Round trip of every StatusCode.
  for (const Status& original :
       {InvalidArgument("a"), FailedPrecondition("b"), OutOfRange("c"), NotFound("d"), Unavailable("e"), Internal("f"),
        PermissionDenied("g"), ResourceExhausted("h"), Cancelled("i")}) {
    const Status back = wire::FromGrpcStatus(wire::ToGrpcStatus(original));
    EXPECT_EQ(back.code(), original.code());
    EXPECT_EQ(back.message(), original.ToString());
  }
}

TEST(ProxyReset, AResetFromTheProxyReadsAsUnavailableAndNothingElseChanges) {
  // What gRPC reports when nginx resets a stream because its upstream died.
  const grpc::Status reset(grpc::StatusCode::INTERNAL, "Received RST_STREAM with error code 2");
  const grpc::Status mapped = FromProxyReset(reset);
  EXPECT_EQ(mapped.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_NE(mapped.error_message().find("instance behind the proxy is gone"), std::string::npos);
  EXPECT_NE(mapped.error_message().find("RST_STREAM with error code 2"), std::string::npos);
  // A server's own INTERNAL (an engine failure), other reset codes and other statuses pass.
  for (const grpc::Status& other :
       {grpc::Status(grpc::StatusCode::INTERNAL, "engine: non-finite covariance"),
        grpc::Status(grpc::StatusCode::INTERNAL, "Received RST_STREAM with error code 8"),
        grpc::Status(grpc::StatusCode::UNAVAILABLE, "server shutting down"),
        grpc::Status(grpc::StatusCode::CANCELLED, "Received RST_STREAM with error code 2"), grpc::Status::OK}) {
    const grpc::Status same = FromProxyReset(other);
    EXPECT_EQ(same.error_code(), other.error_code());
    EXPECT_EQ(same.error_message(), other.error_message());
  }
}

TEST(LatencySummary, NearestRankPercentiles) {
  std::vector<double> latencies;
  for (int i = 100; i >= 1; --i) latencies.push_back(i * 1e-3);  // 1..100 ms, unsorted
  latencies.push_back(std::numeric_limits<double>::quiet_NaN());
  const LatencySummary s = SummariseLatencies(latencies);
  EXPECT_EQ(s.count, 100);
  EXPECT_EQ(s.unknown, 1);
  EXPECT_DOUBLE_EQ(s.p50_s, 50e-3);
  EXPECT_DOUBLE_EQ(s.p95_s, 95e-3);
  EXPECT_DOUBLE_EQ(s.p99_s, 99e-3);
  EXPECT_DOUBLE_EQ(s.max_s, 100e-3);
  EXPECT_EQ(SummariseLatencies({}).count, 0);
}

TEST(ChannelMajorSource, CutsBlocksAndEnds) {
  const std::vector<float> samples = {0, 1, 2, 3, 4, 10, 11, 12, 13, 14};  // 2 channels x 5
  SampleSource source = ChannelMajorSource(samples.data(), 2, 5);
  std::vector<float> block;
  ASSERT_EQ(*source(3, &block), 3);
  EXPECT_EQ(block, (std::vector<float>{0, 1, 2, 10, 11, 12}));
  ASSERT_EQ(*source(3, &block), 2);
  EXPECT_EQ(block, (std::vector<float>{3, 4, 13, 14}));
  EXPECT_EQ(*source(3, &block), 0);
}

}  // namespace
}  // namespace localizer::client
