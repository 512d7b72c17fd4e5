// The session runners without a server: the factory picks the kind from the config, each
// runner says what it is (SessionInfo, the sessions JSON) and refuses in band the requests
// its kind does not take; an audio runner decodes a block against its array and turns it
// into estimates, a detection runner a scan into a track list.
#include "server/service/session_runner.h"

#include <gtest/gtest.h>

#include "server/metrics/registry.h"
#include "wire/block_wire.h"
#include "wire/scan_wire.h"

namespace localizer::server {
namespace {

engine::AudioSessionConfig Audio() {
  engine::AudioSessionConfig c;
  c.sensors_m = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  c.sound_speed_mps = 1500.0;
  c.sample_rate_hz = 8000.0;
  c.frame_samples = 256;
  c.hop_samples = 256;
  c.tracker.particle.particles = 256;
  c.backend = engine::BackendChoice::kCpu;
  return c;
}

engine::SessionConfig AudioConfig() { return Audio(); }

engine::SessionConfig DetectionConfig() { return engine::DetectionSessionConfig{}; }

class SessionRunnerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto made = ServiceMetrics::Create(&registry_, "cpu");
    ASSERT_TRUE(made.ok()) << made.status().ToString();
    metrics_ = std::move(made).value();
  }
  metrics::Registry registry_;
  std::unique_ptr<ServiceMetrics> metrics_;
  const Clock::time_point now_ = Clock::now();
};

Rejection Refusal(const WorkItem& item) {
  EXPECT_TRUE(std::holds_alternative<Rejection>(item.work));
  const auto* r = std::get_if<Rejection>(&item.work);
  return r != nullptr ? *r : Rejection{};
}

v1::SampleBlock Block(uint64_t sequence, int channels, int frames) {
  std::vector<float> samples(static_cast<size_t>(channels * frames), 0.0f);
  for (size_t i = 0; i < samples.size(); ++i) samples[i] = 0.01f * static_cast<float>(i % 17);
  engine::BlockView view{sequence, channels, frames, samples.data()};
  v1::SampleBlock block;
  wire::EncodeBlock(view, /*pcm16=*/false, &block);
  return block;
}

TEST_F(SessionRunnerTest, AnAudioConfigMakesAnAudioRunner) {
  auto runner = MakeSessionRunner(AudioConfig(), metrics_.get());
  ASSERT_TRUE(runner.ok()) << runner.status().ToString();
  const RunnerInfo& info = (*runner)->info();
  EXPECT_EQ(info.kind, "samples");
  EXPECT_EQ(info.backend, "cpu");
  EXPECT_EQ(info.channel_count, 4);
  EXPECT_EQ(info.filter_type, engine::FilterKindName(Audio().tracker.kind));
  EXPECT_TRUE(info.reports_presence);
  EXPECT_EQ((*runner)->config().sensors_m.size(), 4u);  // the audio config it was made from
}

TEST_F(SessionRunnerTest, ADetectionConfigMakesADetectionRunner) {
  auto runner = MakeSessionRunner(DetectionConfig(), metrics_.get());
  ASSERT_TRUE(runner.ok()) << runner.status().ToString();
  const RunnerInfo& info = (*runner)->info();
  EXPECT_EQ(info.kind, "detections");
  EXPECT_EQ(info.filter_type, "tws");
  EXPECT_EQ(info.backend, "cpu");
  EXPECT_EQ(info.channel_count, 0);
  EXPECT_FALSE(info.reports_presence);
  EXPECT_TRUE((*runner)->config().sensors_m.empty());  // a detection session has no array
  EXPECT_TRUE((*runner)->EffectiveConfig("x").has_detections());
}

TEST_F(SessionRunnerTest, ABadConfigIsTheEnginesError) {
  engine::AudioSessionConfig bad = Audio();
  bad.sensors_m.pop_back();  // three sensors: no position
  bad.localization = engine::Localization::kPosition;
  auto runner = MakeSessionRunner(bad, metrics_.get());
  ASSERT_FALSE(runner.ok());
  EXPECT_EQ(runner.status().code(), StatusCode::kInvalidArgument);
}

TEST_F(SessionRunnerTest, EachKindRefusesWhatItDoesNotTake) {
  auto audio = std::move(MakeSessionRunner(AudioConfig(), metrics_.get())).value();
  auto detections = std::move(MakeSessionRunner(DetectionConfig(), metrics_.get())).value();
  v1::TrackRequest scan;
  scan.mutable_scan()->set_sequence(3);
  v1::TrackRequest imu;
  imu.mutable_imu()->set_sequence(4);
  v1::TrackRequest block;
  *block.mutable_block() = Block(5, 4, 64);
  wire::DecodedBlock scratch;

  const Rejection not_detections = Refusal(audio->Decode(scan, now_, &scratch));
  EXPECT_EQ(not_detections.reason, "not_detections");
  EXPECT_EQ(not_detections.request, RequestKind::kScan);
  EXPECT_EQ(not_detections.sequence, 3u);
  EXPECT_EQ(not_detections.status.code(), StatusCode::kFailedPrecondition);

  const Rejection fixed = Refusal(audio->Decode(imu, now_, &scratch));  // a fixed array
  EXPECT_EQ(fixed.reason, "not_moving");
  EXPECT_EQ(fixed.request, RequestKind::kImu);
  EXPECT_EQ(fixed.sequence, 4u);

  const Rejection not_samples = Refusal(detections->Decode(block, now_, &scratch));
  EXPECT_EQ(not_samples.reason, "not_samples");
  EXPECT_EQ(not_samples.request, RequestKind::kBlock);
  EXPECT_EQ(not_samples.sequence, 5u);
  EXPECT_EQ(not_samples.status.code(), StatusCode::kFailedPrecondition);

  EXPECT_EQ(Refusal(detections->Decode(imu, now_, &scratch)).reason, "not_moving");

  // The refusal as the stream writes it.
  const ResponsePtr response = RejectionResponse(not_samples);
  ASSERT_TRUE(response->has_rejected());
  EXPECT_EQ(response->rejected().request(), "block");
  EXPECT_EQ(response->rejected().reason(), "not_samples");
  EXPECT_EQ(response->rejected().code(), "FAILED_PRECONDITION");
  EXPECT_EQ(response->rejected().sequence(), 5u);
}

TEST_F(SessionRunnerTest, AudioBlocksAreDecodedAgainstTheArrayAndGiveEstimates) {
  auto audio = std::move(MakeSessionRunner(AudioConfig(), metrics_.get())).value();
  wire::DecodedBlock scratch;
  v1::TrackRequest bad;
  *bad.mutable_block() = Block(1, 3, 64);  // three channels for four sensors
  const Rejection refused = Refusal(audio->Decode(bad, now_, &scratch));
  EXPECT_EQ(refused.reason, "channel_count");
  EXPECT_EQ(refused.request, RequestKind::kBlock);

  v1::TrackRequest good;
  *good.mutable_block() = Block(2, 4, 512);
  WorkItem item = audio->Decode(good, now_, &scratch);
  ASSERT_TRUE(std::holds_alternative<BlockWork>(item.work));
  EXPECT_EQ(std::get<BlockWork>(item.work).sequence, 2u);
  EXPECT_EQ(std::get<BlockWork>(item.work).samples_per_channel, 512);
  EXPECT_EQ(std::get<BlockWork>(item.work).samples.size(), 4u * 512u);

  TrackHistory track;
  std::vector<ResponsePtr> out;
  audio->Process(item, now_, &track, &out);
  ASSERT_EQ(out.size(), 2u);  // 512 samples, frames of 256 every 256
  for (const ResponsePtr& r : out) {
    ASSERT_TRUE(r->has_estimate());
    EXPECT_EQ(r->estimate().sequence(), 2u);
    EXPECT_EQ(r->estimate().backend(), "cpu");
  }
  EXPECT_EQ(out[1]->estimate().frame_index(), 1u);
  EXPECT_EQ(track.Snapshot().frames, 2u);
}

TEST_F(SessionRunnerTest, ScansBecomeTrackLists) {
  auto detections = std::move(MakeSessionRunner(DetectionConfig(), metrics_.get())).value();
  wire::DecodedBlock scratch;
  engine::Scan scan;
  scan.time_s = 1.0;
  scan.detections.push_back({});
  scan.detections.back().range_m = 1000.0;
  v1::TrackRequest request;
  wire::EncodeScan(scan, 7, request.mutable_scan());
  WorkItem item = detections->Decode(request, now_, &scratch);
  ASSERT_TRUE(std::holds_alternative<ScanWork>(item.work));

  TrackHistory track;
  std::vector<ResponsePtr> out;
  detections->Process(item, now_, &track, &out);
  ASSERT_EQ(out.size(), 1u);
  ASSERT_TRUE(out[0]->has_tracks());
  EXPECT_EQ(out[0]->tracks().sequence(), 7u);
  EXPECT_EQ(out[0]->tracks().tracks_size(), 1);  // one plot starts one tentative track
  EXPECT_EQ(track.Snapshot().targets.size(), 1u);

  // A scan not after the previous one is the engine's refusal, in band.
  out.clear();
  WorkItem again = detections->Decode(request, now_, &scratch);
  detections->Process(again, now_, &track, &out);
  ASSERT_EQ(out.size(), 1u);
  ASSERT_TRUE(out[0]->has_rejected());
  EXPECT_EQ(out[0]->rejected().reason(), "scan");
  EXPECT_EQ(out[0]->rejected().request(), "scan");
}

}  // namespace
}  // namespace localizer::server
