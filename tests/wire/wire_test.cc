// wire/: frame-major <-> channel-major blocks (float and 16-bit PCM), the rules a
// bad block breaks, estimates (model probabilities, presence, range, sources) both ways, IMU
// batch limits, Locate's request and response, Status -> gRPC codes. Configs:
// config_wire_test.cc.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <tuple>
#include <variant>
#include <vector>

#include "tests/wire/minimal_config.h"
#include "wire/block_wire.h"
#include "wire/config_wire.h"
#include "wire/estimate_wire.h"
#include "wire/imu_wire.h"
#include "wire/locate_wire.h"
#include "wire/status_wire.h"
#include "wire/string_limits.h"

namespace localizer::wire {
namespace {

using testing::MinimalConfig;

v1::SampleBlock InterleavedBlock(int channels, int frames) {
  v1::SampleBlock block;
  block.set_sequence(7);
  block.set_channel_count(static_cast<uint32_t>(channels));
  for (int i = 0; i < frames; ++i) {
    for (int c = 0; c < channels; ++c) block.add_samples(static_cast<float>(100 * c + i));
  }
  return block;
}

TEST(BlockWire, DecodeDeinterleavesToChannelMajor) {
  DecodedBlock out;
  std::string reason;
  ASSERT_TRUE(DecodeBlock(InterleavedBlock(4, 5), {4, 1000}, &out, &reason).ok());
  EXPECT_EQ(out.view.sequence, 7u);
  EXPECT_EQ(out.view.channel_count, 4);
  EXPECT_EQ(out.view.samples_per_channel, 5);
  for (int c = 0; c < 4; ++c) {
    for (int i = 0; i < 5; ++i) EXPECT_EQ(out.view.samples[c * 5 + i], static_cast<float>(100 * c + i));
  }
}

TEST(BlockWire, EncodeThenDecodeIsIdentityForFloats) {
  std::vector<float> channel_major(3 * 8);
  for (size_t i = 0; i < channel_major.size(); ++i) channel_major[i] = std::sin(0.37f * static_cast<float>(i));
  v1::SampleBlock block;
  EncodeBlock({9, 3, 8, channel_major.data()}, false, &block);
  EXPECT_EQ(block.samples(1), channel_major[8]);  // frame 0, channel 1
  DecodedBlock out;
  std::string reason;
  ASSERT_TRUE(DecodeBlock(block, {3, 8}, &out, &reason).ok());
  EXPECT_EQ(out.samples, channel_major);
}

TEST(BlockWire, Pcm16IsLittleEndianOver32768AndClips) {
  const std::vector<float> channel_major = {0.5f, -1.0f, 2.0f, -0.25f};  // 2 channels x 2 samples
  v1::SampleBlock block;
  EncodeBlock({1, 2, 2, channel_major.data()}, true, &block);
  ASSERT_EQ(block.pcm_s16le().size(), 8u);
  EXPECT_EQ(block.samples_size(), 0);
  // Frame 0: ch0 0.5 -> 16384 = 0x4000, ch1 2.0 clips to 32767 = 0x7fff.
  EXPECT_EQ(static_cast<unsigned char>(block.pcm_s16le()[0]), 0x00);
  EXPECT_EQ(static_cast<unsigned char>(block.pcm_s16le()[1]), 0x40);
  EXPECT_EQ(static_cast<unsigned char>(block.pcm_s16le()[2]), 0xff);
  EXPECT_EQ(static_cast<unsigned char>(block.pcm_s16le()[3]), 0x7f);
  DecodedBlock out;
  std::string reason;
  ASSERT_TRUE(DecodeBlock(block, {2, 2}, &out, &reason).ok());
  EXPECT_EQ(out.samples[0], 0.5f);
  EXPECT_EQ(out.samples[1], -1.0f);
  EXPECT_EQ(out.samples[2], 32767.0f / 32768.0f);
  EXPECT_EQ(out.samples[3], -0.25f);
}

TEST(BlockWire, EachBrokenRuleHasItsReason) {
  DecodedBlock out;
  std::string reason;
  v1::SampleBlock block = InterleavedBlock(4, 5);
  block.set_channel_count(3);
  EXPECT_EQ(DecodeBlock(block, {4, 1000}, &out, &reason).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(reason, "channel_count");
  // Zero channels against limits of zero channels (a session that takes no samples): a
  // rejection, not a division by zero.
  block = InterleavedBlock(4, 5);
  block.set_channel_count(0);
  EXPECT_EQ(DecodeBlock(block, {0, 0}, &out, &reason).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(reason, "channel_count");

  block = InterleavedBlock(4, 5);
  block.add_samples(1.0f);
  EXPECT_FALSE(DecodeBlock(block, {4, 1000}, &out, &reason).ok());
  EXPECT_EQ(reason, "bad_samples");

  block = InterleavedBlock(4, 5);
  block.set_pcm_s16le(std::string(40, '\0'));
  EXPECT_FALSE(DecodeBlock(block, {4, 1000}, &out, &reason).ok());
  EXPECT_EQ(reason, "bad_samples");

  block = InterleavedBlock(4, 5);
  block.set_samples(13, INFINITY);
  const Status status = DecodeBlock(block, {4, 1000}, &out, &reason);
  EXPECT_EQ(reason, "non_finite");
  EXPECT_NE(status.message().find("samples[13] (frame 3, channel 1)"), std::string::npos) << status.message();

  EXPECT_FALSE(DecodeBlock(InterleavedBlock(4, 5), {4, 4}, &out, &reason).ok());
  EXPECT_EQ(reason, "oversize");

  block = InterleavedBlock(4, 0);
  EXPECT_FALSE(DecodeBlock(block, {4, 1000}, &out, &reason).ok());
  EXPECT_EQ(reason, "empty");
}

TEST(EstimateWire, ModelProbabilitiesRoundTrip) {
  const engine::ArrayGeometry array =
      *engine::ArrayGeometry::Create({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, 1500.0);
  engine::Estimate e;
  e.frame_index = 4;
  e.initialised = true;
  e.state << 1, 2, 3, 0.1, 0.2, 0.3;
  e.model_probabilities = {{"cv", 0.25}, {"ct", 0.75}};
  v1::Estimate wire;
  EstimateToProto(e, array.reference_sensor(), "cpu", &wire);
  ASSERT_EQ(wire.model_probabilities_size(), 2);
  EXPECT_EQ(wire.model_probabilities(1).model(), "ct");
  EXPECT_EQ(wire.model_probabilities(1).probability(), 0.75);
  // A reused message is refilled, not appended to.
  EstimateToProto(e, array.reference_sensor(), "cpu", &wire);
  EXPECT_EQ(wire.model_probabilities_size(), 2);
  const engine::Estimate back = EstimateFromProto(wire);
  ASSERT_EQ(back.model_probabilities.size(), 2u);
  EXPECT_EQ(back.model_probabilities[0].model, "cv");
  EXPECT_EQ(back.model_probabilities[0].probability, 0.25);
  EXPECT_EQ(back.state, e.state);
  // Single-model filters: no entries on the wire.
  e.model_probabilities.clear();
  EstimateToProto(e, array.reference_sensor(), "cpu", &wire);
  EXPECT_EQ(wire.model_probabilities_size(), 0);
}

TEST(EstimateWire, PresenceAmbiguityAndRangeRoundTrip) {
  const engine::ArrayGeometry array =
      *engine::ArrayGeometry::Create({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, 1500.0);
  engine::Estimate e;
  e.initialised = true;
  e.source_present = true;
  e.presence_statistic = 12.5;
  e.presence_threshold = 4.25;
  e.ambiguous = true;
  e.modes = 2;
  e.far_field = true;
  e.range_sd_m = 7.5;
  v1::Estimate wire;
  EstimateToProto(e, array.reference_sensor(), "cpu", &wire);
  EXPECT_TRUE(wire.far_field());
  EXPECT_EQ(wire.range_sd_m(), 7.5);
  EXPECT_TRUE(wire.source_present());
  EXPECT_EQ(wire.presence_statistic(), 12.5);
  EXPECT_EQ(wire.presence_threshold(), 4.25);
  EXPECT_TRUE(wire.ambiguous());
  EXPECT_EQ(wire.modes(), 2u);
  engine::Estimate back = EstimateFromProto(wire);
  EXPECT_TRUE(back.source_present);
  EXPECT_EQ(back.presence_statistic, 12.5);
  EXPECT_EQ(back.presence_threshold, 4.25);
  EXPECT_TRUE(back.ambiguous);
  EXPECT_EQ(back.modes, 2);
  EXPECT_TRUE(back.far_field);
  EXPECT_EQ(back.range_sd_m, 7.5);
  // A silent, uninitialised frame: all false / zero, and a reused message is overwritten.
  engine::Estimate silent;
  silent.presence_statistic = 1.5;
  silent.presence_threshold = 4.25;
  EstimateToProto(silent, array.reference_sensor(), "cpu", &wire);
  EXPECT_FALSE(wire.source_present());
  EXPECT_FALSE(wire.ambiguous());
  EXPECT_EQ(wire.modes(), 0u);
  EXPECT_FALSE(wire.far_field());
  EXPECT_EQ(wire.range_sd_m(), 0.0);
  back = EstimateFromProto(wire);
  EXPECT_FALSE(back.source_present);
  EXPECT_EQ(back.presence_statistic, 1.5);
  EXPECT_EQ(back.modes, 0);
}

// Direction sessions: the config fields round-trip, bad values are named, and an
// estimate's sources survive the wire (NaN where the array cannot observe).
TEST(EstimateWire, SourcesRoundTrip) {
  engine::Estimate e;
  e.source_present = true;
  engine::SourceEstimate a;
  a.source_id = 3;
  a.status = engine::TrackStatus::kCoasting;
  a.direction = engine::Vec3(0.6, 0.8, 0.0);
  a.azimuth_rad = 0.927;
  a.elevation_rad = 0.0;
  a.sigma_rad = 0.02;
  engine::SourceEstimate line;  // a linear array's: the cone angle only
  line.source_id = 4;
  line.status = engine::TrackStatus::kConfirmed;
  line.cone_angle_rad = 1.2;
  line.source_present = true;
  line.power_db = 9.5;
  e.sources = {a, line};
  v1::Estimate wire;
  EstimateToProto(e, 0, "cpu", &wire);
  ASSERT_EQ(wire.sources_size(), 2);
  EXPECT_EQ(wire.sources(0).status(), v1::TRACK_STATUS_COASTING);
  EXPECT_EQ(wire.sources(1).status(), v1::TRACK_STATUS_CONFIRMED);
  const engine::Estimate back = EstimateFromProto(wire);
  ASSERT_EQ(back.sources.size(), 2u);
  EXPECT_EQ(back.sources[0].source_id, 3u);
  EXPECT_EQ(back.sources[0].status, engine::TrackStatus::kCoasting);
  EXPECT_EQ(back.sources[0].direction, a.direction);
  EXPECT_DOUBLE_EQ(back.sources[0].azimuth_rad, 0.927);
  EXPECT_TRUE(std::isnan(back.sources[0].power_db));
  EXPECT_FALSE(back.sources[0].source_present);
  EXPECT_TRUE(std::isnan(back.sources[1].azimuth_rad));
  EXPECT_DOUBLE_EQ(back.sources[1].cone_angle_rad, 1.2);
  EXPECT_DOUBLE_EQ(back.sources[1].power_db, 9.5);
  EXPECT_FALSE(wire.sources(0).has_position_m());  // none bounded: unset, not zeros
  EXPECT_FALSE(back.sources[0].position_m.allFinite());
  // A reused message is overwritten, not appended to.
  EstimateToProto(engine::Estimate{}, 0, "cpu", &wire);
  EXPECT_EQ(wire.sources_size(), 0);
}

// Positions from a planar or linear array: position, covariance and range sd per source.
TEST(EstimateWire, SourcePositionsRoundTrip) {
  engine::Estimate e;
  engine::SourceEstimate s;
  s.source_id = 2;
  s.cone_angle_rad = 1.1;
  s.position_m = engine::Vec3(1.0, 2.0, 1.5);
  s.position_covariance_m2 = engine::Mat3::Identity() * 1e-4;
  s.position_covariance_m2(0, 1) = s.position_covariance_m2(1, 0) = 2e-5;
  s.range_sd_m = 0.012;
  e.sources = {s};
  v1::Estimate wire;
  EstimateToProto(e, 0, "cpu", &wire);
  ASSERT_TRUE(wire.sources(0).has_position_m());
  EXPECT_EQ(wire.sources(0).position_covariance_size(), 9);
  const engine::Estimate back = EstimateFromProto(wire);
  EXPECT_EQ(back.sources[0].position_m, s.position_m);
  EXPECT_EQ(back.sources[0].position_covariance_m2, s.position_covariance_m2);
  EXPECT_DOUBLE_EQ(back.sources[0].range_sd_m, 0.012);
}

TEST(ImuWire, ABatchAboveTheSampleLimitIsInvalidArgumentNamingIt) {
  std::vector<engine::ImuSample> samples(kMaxImuSamplesPerBatch + 1);
  for (size_t i = 0; i < samples.size(); ++i) samples[i].t_s = 1e-3 * static_cast<double>(i + 1);
  v1::ImuBatch batch;
  EncodeImuBatch(samples, nullptr, 1, &batch);
  const auto refused = DecodeImuBatch(batch);
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(refused.status().message().find("imu.samples"), std::string::npos) << refused.status().message();
  samples.pop_back();
  EncodeImuBatch(samples, nullptr, 1, &batch);
  EXPECT_TRUE(DecodeImuBatch(batch).ok());
}

TEST(StatusWire, CodesMapByName) {
  for (StatusCode code : {StatusCode::kInvalidArgument, StatusCode::kFailedPrecondition, StatusCode::kOutOfRange,
                          StatusCode::kNotFound, StatusCode::kUnavailable, StatusCode::kInternal,
                          StatusCode::kPermissionDenied, StatusCode::kResourceExhausted, StatusCode::kCancelled}) {
    const grpc::Status g = ToGrpcStatus(Status(code, "m"));
    EXPECT_STREQ(GrpcCodeName(g.error_code()), StatusCodeName(code));
    EXPECT_EQ(g.error_message(), "m");
  }
  EXPECT_TRUE(ToGrpcStatus(Status::Ok()).ok());
}

TEST(LocateWire, DetectionConfigsAndBadBlocksAreInvalidArgumentNamingTheField) {
  v1::LocateRequest request;
  request.mutable_config()->mutable_detections();
  DecodedLocate decoded;
  Status status = DecodeLocateRequest(request, ConfigPolicy{}, &decoded);
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("config.detections"), std::string::npos) << status.message();

  *request.mutable_config() = MinimalConfig();
  *request.mutable_block() = InterleavedBlock(3, 100);  // the array has 4 sensors
  status = DecodeLocateRequest(request, ConfigPolicy{}, &decoded);
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);

  *request.mutable_block() = InterleavedBlock(4, 100);
  ASSERT_TRUE(DecodeLocateRequest(request, ConfigPolicy{}, &decoded).ok());
  EXPECT_EQ(decoded.config.sensors_m.size(), 4u);
  EXPECT_EQ(decoded.block.view.channel_count, 4);
  EXPECT_EQ(decoded.block.view.samples_per_channel, 100);
  EXPECT_EQ(decoded.block.view.samples[100], 100.0f);  // channel 1, sample 0
}

TEST(LocateWire, ResultFillsPairsFixAndCovariance) {
  // Reference sensor 1: pairs are (1, 0), (1, 2), (1, 3).
  const std::vector<engine::Vec3> sensors = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  auto array = engine::ArrayGeometry::Create(sensors, 1500.0, 1);
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  engine::LocateResult result;
  for (int p = 0; p < 3; ++p) {
    engine::PairMeasurement m;
    m.delay_s = 1e-4 * (p + 1);
    m.quality = 2.0 + p;
    m.peak_snr = 10.0 + p;
    result.measurement.pairs.push_back(m);
  }
  result.tdoa_s = 0.004;
  v1::LocateResponse response;
  LocateResultToProto(result, *array, &response);
  ASSERT_EQ(response.pairs_size(), 3);
  EXPECT_EQ(response.pairs(0).sensor(), 0u);
  EXPECT_EQ(response.pairs(1).sensor(), 2u);
  EXPECT_EQ(response.pairs(2).sensor(), 3u);
  EXPECT_EQ(response.pairs(2).delay_s(), result.measurement.pairs[2].delay_s);
  EXPECT_EQ(response.pairs(1).quality(), 3.0);
  EXPECT_EQ(response.pairs(0).peak_snr(), 10.0);
  EXPECT_FALSE(response.fix_found());
  EXPECT_FALSE(response.has_position_m());
  EXPECT_EQ(response.covariance_size(), 0);
  EXPECT_EQ(response.tdoa_s(), 0.004);

  result.fix_found = true;
  result.fix.position_m = engine::Vec3(1.0, 2.0, 3.0);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) result.fix.covariance_m2(r, c) = 10.0 * r + c;
  }
  result.fix.rms_residual_s = 2e-6;
  response.Clear();
  LocateResultToProto(result, *array, &response);
  EXPECT_TRUE(response.fix_found());
  EXPECT_EQ(response.position_m().y(), 2.0);
  ASSERT_EQ(response.covariance_size(), 9);
  EXPECT_EQ(response.covariance(5), 12.0);  // row 1, column 2: row-major
  EXPECT_EQ(response.residual_rms_s(), 2e-6);
}

}  // namespace
}  // namespace localizer::wire