// Bad requests: a bad block is answered with BlockRejected (exact code and reason) and
// the session goes on producing estimates; a bad open or a block before open ends the
// stream with the documented status.
#include "engine/pipeline/backend.h"
#include "tests/server/service_fixture.h"

namespace localizer::server::testing {
namespace {

constexpr int64_t kBlock = 2048;

class BadInputTest : public ServiceTest {
 protected:
  // Opens a session with max_block_samples 8192, sends blocks 1..3, then `bad`, then
  // blocks 4..8; returns the rejection and checks estimates kept coming after it.
  v1::BlockRejected RejectOnce(const v1::TrackRequest& bad) {
    TestStream stream(stub_.get());
    v1::TrackRequest open = scenario_.OpenRequest();
    open.mutable_open()->set_max_block_samples(8192);
    EXPECT_TRUE(stream.Send(open));
    for (int64_t k = 1; k <= 3; ++k) EXPECT_TRUE(stream.Send(scenario_.BlockRequest(k, kBlock)));
    EXPECT_TRUE(stream.WaitForEstimates(2));
    const size_t before = stream.estimates().size();
    EXPECT_TRUE(stream.Send(bad));
    for (int64_t k = 4; k <= 8; ++k) EXPECT_TRUE(stream.Send(scenario_.BlockRequest(k, kBlock)));
    EXPECT_TRUE(stream.Close().ok());
    v1::BlockRejected rejected;
    int rejections = 0;
    size_t estimates_after = 0;
    for (const auto& r : stream.responses()) {
      if (r.has_rejected()) {
        rejected = r.rejected();
        ++rejections;
      }
      if (r.has_estimate() && rejections > 0) ++estimates_after;
    }
    EXPECT_EQ(rejections, 1);
    EXPECT_EQ(estimates_after, 5u) << "the session stopped after the bad block";
    // 8 blocks of 2048 make 7 frames of 4096 (hop 2048); 2 came before the bad block.
    EXPECT_EQ(stream.estimates().size(), before + 5);
    return rejected;
  }

  Scenario scenario_ = MakeScenario("tetra-water", 2.0, 1, kBlock);
};

TEST_F(BadInputTest, WrongChannelCount) {
  v1::TrackRequest bad = scenario_.BlockRequest(4, kBlock);
  bad.mutable_block()->set_channel_count(3);
  bad.mutable_block()->mutable_samples()->Truncate(3 * kBlock);
  const v1::BlockRejected r = RejectOnce(bad);
  EXPECT_EQ(r.code(), "INVALID_ARGUMENT");
  EXPECT_EQ(r.reason(), "channel_count");
  EXPECT_EQ(r.sequence(), 4u);
  EXPECT_NE(r.message().find("channel_count is 3"), std::string::npos) << r.message();
}

TEST_F(BadInputTest, NonFiniteSample) {
  v1::TrackRequest bad = scenario_.BlockRequest(4, kBlock);
  bad.mutable_block()->set_samples(4 * 10 + 2, std::nanf(""));
  const v1::BlockRejected r = RejectOnce(bad);
  EXPECT_EQ(r.code(), "INVALID_ARGUMENT");
  EXPECT_EQ(r.reason(), "non_finite");
  EXPECT_NE(r.message().find("frame 10, channel 2"), std::string::npos) << r.message();
}

TEST_F(BadInputTest, EmptyBlock) {
  v1::TrackRequest bad;
  bad.mutable_block()->set_sequence(4);
  bad.mutable_block()->set_channel_count(4);
  const v1::BlockRejected r = RejectOnce(bad);
  EXPECT_EQ(r.code(), "INVALID_ARGUMENT");
  EXPECT_EQ(r.reason(), "empty");
}

TEST_F(BadInputTest, OversizeBlock) {
  v1::TrackRequest bad = scenario_.BlockRequest(4, kBlock);
  bad.mutable_block()->mutable_samples()->Resize(4 * 9000, 0.0f);  // limit is 8192 per channel
  const v1::BlockRejected r = RejectOnce(bad);
  EXPECT_EQ(r.code(), "INVALID_ARGUMENT");
  EXPECT_EQ(r.reason(), "oversize");
  EXPECT_NE(r.message().find("8192"), std::string::npos) << r.message();
}

TEST_F(BadInputTest, RaggedSampleCount) {
  v1::TrackRequest bad = scenario_.BlockRequest(4, kBlock);
  bad.mutable_block()->add_samples(0.0f);
  const v1::BlockRejected r = RejectOnce(bad);
  EXPECT_EQ(r.reason(), "bad_samples");
}

TEST_F(BadInputTest, DuplicateSequenceChangesNothing) {
  const v1::BlockRejected r = RejectOnce(scenario_.BlockRequest(3, kBlock));
  EXPECT_EQ(r.code(), "INVALID_ARGUMENT");
  EXPECT_EQ(r.reason(), "duplicate");
  EXPECT_EQ(r.sequence(), 3u);
}

TEST_F(BadInputTest, OutOfOrderSequence) {
  const v1::BlockRejected r = RejectOnce(scenario_.BlockRequest(2, kBlock));
  EXPECT_EQ(r.reason(), "out_of_order");
}

TEST_F(ServiceTest, DuplicateLeavesEstimatesIdenticalToACleanRun) {
  const Scenario s = MakeScenario("tetra-water", 2.0, 2, kBlock);
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(s.OpenRequest()));
  for (int64_t k = 1; k <= s.BlockCount(kBlock); ++k) {
    ASSERT_TRUE(stream.Send(s.BlockRequest(k, kBlock)));
    if (k == 5) {
      ASSERT_TRUE(stream.Send(s.BlockRequest(k, kBlock)));  // resent after a "reconnect"
    }
  }
  ASSERT_TRUE(stream.Close().ok());
  const auto estimates = stream.estimates();
  ASSERT_EQ(estimates.size(), s.offline.size());
  for (size_t i = 0; i < estimates.size(); ++i) ExpectSameEstimate(s.offline[i], estimates[i]);
}

TEST_F(ServiceTest, SequenceGapIsReportedAndTimeSkipsAhead) {
  const Scenario s = MakeScenario("tetra-water", 3.0, 1, kBlock);
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(s.OpenRequest()));
  for (int64_t k = 1; k <= s.BlockCount(kBlock); ++k) {
    if (k == 6 || k == 7) continue;  // lost upstream
    ASSERT_TRUE(stream.Send(s.BlockRequest(k, kBlock)));
  }
  ASSERT_TRUE(stream.Close().ok());
  v1::SequenceGap gap;
  int gaps = 0;
  for (const auto& r : stream.responses()) {
    if (r.has_gap()) {
      gap = r.gap();
      ++gaps;
    }
  }
  ASSERT_EQ(gaps, 1);
  EXPECT_EQ(gap.previous_sequence(), 5u);
  EXPECT_EQ(gap.sequence(), 8u);
  EXPECT_EQ(gap.missing_blocks(), 2u);
  EXPECT_EQ(gap.skipped_samples(), 2u * kBlock);
  // Every estimate's t_s is where its samples really were: the first frame after the gap
  // starts at block 8's first sample.
  const auto estimates = stream.estimates();
  const double fs = s.config.sample_rate_hz;
  bool found = false;
  for (const auto& e : estimates) {
    if (e.sequence() >= 8) {
      EXPECT_NEAR(e.t_s(), (7.0 * kBlock + 0.5 * (4096 - 1)) / fs, 1e-9);
      found = true;
      break;
    }
  }
  EXPECT_TRUE(found);
  EXPECT_TRUE(estimates.back().initialised());
}

TEST_F(ServiceTest, BlockBeforeOpenIsFailedPrecondition) {
  const Scenario s = MakeScenario("tetra-water", 1.0, 1, kBlock);
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(s.BlockRequest(1, kBlock)));
  const grpc::Status status = stream.Close();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("before open"), std::string::npos) << status.error_message();
}

TEST_F(ServiceTest, BadConfigsAreInvalidArgumentNamingTheField) {
  const Scenario s = MakeScenario("tetra-water", 1.0, 1, kBlock);
  struct Case {
    std::function<void(v1::SessionConfig*)> spoil;
    std::string field;
  };
  const std::vector<Case> cases = {
      // Positions need 4 sensors off a common plane (fewer, or coplanar: directions).
      {[](v1::SessionConfig* c) {
         c->mutable_array()->mutable_sensors_m()->RemoveLast();
         c->set_localization("position");
       },
       "array.sensors_m"},
      {[](v1::SessionConfig* c) {
         for (auto& p : *c->mutable_array()->mutable_sensors_m()) p.set_z(0.0);  // coplanar
         c->set_localization("position");
       },
       "planar"},
      {[](v1::SessionConfig* c) { c->set_localization("everywhere"); }, "localization"},
      {[](v1::SessionConfig* c) { c->set_max_sources(99); }, "max_sources"},
      {[](v1::SessionConfig* c) { c->set_sample_rate_hz(-1.0); }, "sample_rate_hz"},
      {[](v1::SessionConfig* c) { c->mutable_array()->set_sound_speed_mps(0.0); }, "sound_speed_mps"},
      {[](v1::SessionConfig* c) { c->set_frame_samples(16); }, "frame_samples"},
      {[](v1::SessionConfig* c) { c->set_hop_samples(8192); }, "hop_samples"},
      // One sample per hop: a block would cost frame_samples times the work of hop = frame.
      {[](v1::SessionConfig* c) { c->set_hop_samples(1); }, "frame_samples/64"},
      {[](v1::SessionConfig* c) { c->set_backend("tpu"); }, "backend"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.field);
    v1::TrackRequest open = s.OpenRequest();
    c.spoil(open.mutable_open());
    TestStream stream(stub_.get());
    ASSERT_TRUE(stream.Send(open));
    const grpc::Status status = stream.Close();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(status.error_message().find(c.field), std::string::npos) << status.error_message();
  }
}

// The status of an open spoiled by `spoil`.
grpc::Status OpenStatus(v1::Localizer::Stub* stub, const Scenario& s,
                        const std::function<void(v1::SessionConfig*)>& spoil) {
  v1::TrackRequest open = s.OpenRequest();
  spoil(open.mutable_open());
  TestStream stream(stub);
  EXPECT_TRUE(stream.Send(open));
  return stream.Close();
}

TEST_F(ServiceTest, BadNumbersAreInvalidArgumentNamingTheField) {
  const Scenario s = MakeScenario("tetra-water", 1.0, 1, kBlock);
  struct Case {
    std::function<void(v1::SessionConfig*)> spoil;
    std::vector<std::string> expect;  // substrings of the message
  };
  const std::vector<Case> cases = {
      {[](v1::SessionConfig* c) {
         c->mutable_init_region()->mutable_min_m()->set_x(-1e300);
         c->mutable_init_region()->mutable_max_m()->set_x(1e300);
       },
       {"init_region.min_m.x", "1e7"}},
      {[](v1::SessionConfig* c) { c->mutable_init_region()->mutable_max_m()->set_z(1e300); },
       {"init_region.max_m.z", "1e7"}},
      {[](v1::SessionConfig* c) { c->set_weighting(static_cast<v1::Weighting>(99)); }, {"weighting", "99"}},
      {[](v1::SessionConfig* c) { c->mutable_filter()->set_likelihood(static_cast<v1::Likelihood>(-7)); },
       {"filter.likelihood", "-7"}},
      {[](v1::SessionConfig* c) { c->mutable_array()->set_reference_sensor(4294967295u); },
       {"array.reference_sensor", "4294967295"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.expect[0]);
    const grpc::Status status = OpenStatus(stub_.get(), s, c.spoil);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
    for (const std::string& want : c.expect) {
      EXPECT_NE(status.error_message().find(want), std::string::npos) << status.error_message();
    }
    EXPECT_EQ(status.error_message().find("-1 "), std::string::npos) << status.error_message();
  }
}

TEST_F(ServiceTest, OversizedStringsAreInvalidArgumentWithoutEcho) {
  const Scenario s = MakeScenario("tetra-water", 1.0, 1, kBlock);
  const std::string huge = "x\r\nlevel=error event=forged " + std::string(1 << 20, 'Q');
  struct Case {
    std::function<void(v1::SessionConfig*)> spoil;
    std::string field;
    std::string limit;
  };
  const std::vector<Case> cases = {
      {[&](v1::SessionConfig* c) { c->set_label(huge); }, "label", "256"},
      {[&](v1::SessionConfig* c) { c->set_label(std::string(257, 'l')); }, "label", "256"},
      {[&](v1::SessionConfig* c) { c->set_backend(huge); }, "backend", "64"},
      {[&](v1::SessionConfig* c) { c->mutable_filter()->set_motion_model(huge); }, "filter.motion_model", "64"},
      {[&](v1::SessionConfig* c) { c->mutable_filter()->set_imm_modes(huge); }, "filter.imm_modes", "64"},
      {[&](v1::SessionConfig* c) { c->mutable_filter()->set_imm_variant(huge); }, "filter.imm_variant", "64"},
      {[&](v1::SessionConfig* c) { c->mutable_filter()->set_robust(huge); }, "filter.robust", "64"},
      {[&](v1::SessionConfig* c) { c->mutable_platform()->set_attitude_filter(huge); }, "platform.attitude_filter",
       "64"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.field);
    const grpc::Status status = OpenStatus(stub_.get(), s, c.spoil);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message().substr(0, 200);
    EXPECT_NE(status.error_message().find(c.field), std::string::npos) << status.error_message().substr(0, 200);
    EXPECT_NE(status.error_message().find(c.limit), std::string::npos) << status.error_message().substr(0, 200);
    EXPECT_LT(status.error_message().size(), 200u);
    EXPECT_EQ(status.error_message().find_first_of("\r\n"), std::string::npos);
  }
  // At the limit is fine.
  const grpc::Status ok = OpenStatus(stub_.get(), s, [](v1::SessionConfig* c) { c->set_label(std::string(256, 'l')); });
  EXPECT_TRUE(ok.ok()) << ok.error_message();
}

TEST_F(ServiceTest, GpuBackendWithoutADeviceIsFailedPrecondition) {
  if (engine::GpuUnavailableReason().empty()) GTEST_SKIP() << "this machine has a usable GPU";
  const Scenario s = MakeScenario("tetra-water", 1.0, 1, kBlock);
  v1::TrackRequest open = s.OpenRequest();
  open.mutable_open()->set_backend("gpu");
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(open));
  const grpc::Status status = stream.Close();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("gpu"), std::string::npos) << status.error_message();
}

}  // namespace
}  // namespace localizer::server::testing
