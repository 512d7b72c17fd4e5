// Detection sessions over the wire: a session opened with SessionConfig.detections takes
// scans of radar plots and answers each with the track list the engine's ScanSession gives
// offline for the same scans; eight targets in clutter are all confirmed; a bad scan is
// refused in-band (request "scan", the field named) and the session goes on as if it had
// never come; blocks to a detection session and scans to an audio one are refused.
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <random>

#include "engine/pipeline/scan_session.h"
#include "engine/sim/radar_scan.h"
#include "tests/server/http_client.h"
#include "tests/server/service_fixture.h"
#include "wire/scan_wire.h"

namespace localizer::server::testing {
namespace {

constexpr int kScans = 12;

engine::DetectionSessionConfig DetectionConfig() { return {}; }

// Eight targets 5 km apart on a 20 km ring around the radar, clutter ~10 plots a scan.
std::vector<engine::RadarScanFrame> Frames() {
  engine::RadarScanOptions o;
  o.max_range_m = 40000.0;
  o.clutter_density_per_m2 = 2e-9;
  o.seed = 5;
  auto sim = engine::RadarScanSimulator::Create(o, engine::RingTargets(8, 20000.0, 150.0, Eigen::Vector2d::Zero()));
  EXPECT_TRUE(sim.ok());
  std::vector<engine::RadarScanFrame> frames;
  for (int k = 0; k < kScans; ++k) frames.push_back(sim->Frame(k));
  return frames;
}

v1::TrackRequest ScanRequest(const engine::Scan& scan, uint64_t sequence) {
  v1::TrackRequest request;
  wire::EncodeScan(scan, sequence, request.mutable_scan());
  return request;
}

v1::TrackRequest OpenDetections() {
  v1::TrackRequest request;
  *request.mutable_open() = wire::ConfigToProto(DetectionConfig(), "radar");
  return request;
}

std::vector<v1::TrackList> Lists(TestStream& stream) {
  std::vector<v1::TrackList> out;
  for (const auto& r : stream.responses()) {
    if (r.has_tracks()) out.push_back(r.tracks());
  }
  return out;
}

void ExpectSameList(const engine::ScanResult& want, const v1::TrackList& got) {
  EXPECT_EQ(got.scan_index(), want.scan_index);
  EXPECT_EQ(got.time_s(), want.time_s);
  ASSERT_EQ(static_cast<size_t>(got.tracks_size()), want.tracks.size());
  for (size_t i = 0; i < want.tracks.size(); ++i) {
    const v1::TargetTrack& t = got.tracks(static_cast<int>(i));
    EXPECT_EQ(t.id(), want.tracks[i].id);
    EXPECT_EQ(t.position_m().x(), want.tracks[i].position_m.x());
    EXPECT_EQ(t.velocity_mps().y(), want.tracks[i].velocity_mps.y());
    ASSERT_EQ(t.covariance_size(), 36);
    EXPECT_EQ(t.covariance(7), want.tracks[i].covariance(1, 1));
  }
}

class DetectionServiceTest : public ServiceTest {
 protected:
  std::vector<engine::RadarScanFrame> frames_ = Frames();
  std::vector<engine::ScanResult> Offline() const {
    auto session = std::move(*engine::ScanSession::Create(DetectionConfig()));
    std::vector<engine::ScanResult> out(frames_.size());
    for (size_t k = 0; k < frames_.size(); ++k) EXPECT_TRUE(session->Process(frames_[k].scan, &out[k]).ok());
    return out;
  }
};

TEST_F(DetectionServiceTest, TrackListsEqualTheOfflineRunAndEightTargetsAreConfirmed) {
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(OpenDetections()));
  for (size_t k = 0; k < frames_.size(); ++k) {
    if (!stream.Send(ScanRequest(frames_[k].scan, 100 + k))) {
      const grpc::Status s = stream.Close();
      FAIL() << s.error_code() << " " << s.error_message();
    }
  }
  ASSERT_TRUE(stream.Close().ok());
  EXPECT_TRUE(stream.opened().effective_config().has_detections());
  EXPECT_EQ(stream.opened().effective_config().detections().confirm_hits(), 3u);
  const std::vector<v1::TrackList> got = Lists(stream);
  const std::vector<engine::ScanResult> want = Offline();
  ASSERT_EQ(got.size(), want.size());
  for (size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(got[k].sequence(), 100 + k);
    ExpectSameList(want[k], got[k]);
    EXPECT_GE(got[k].total_s(), got[k].process_s());
  }
  int confirmed = 0;
  for (const v1::TargetTrack& t : got.back().tracks()) {
    if (t.status() == v1::TRACK_STATUS_CONFIRMED || t.status() == v1::TRACK_STATUS_COASTING) ++confirmed;
  }
  EXPECT_EQ(confirmed, 8);
}

TEST_F(DetectionServiceTest, LiveViewJsonListsTheLatestTargets) {
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(OpenDetections()));
  for (size_t k = 0; k < frames_.size(); ++k) ASSERT_TRUE(stream.Send(ScanRequest(frames_[k].scan, k)));
  ASSERT_TRUE(stream.WaitFor([&](const auto& rs) {
    size_t lists = 0;
    for (const auto& r : rs) lists += r.has_tracks() ? 1 : 0;
    return lists == frames_.size();
  }));
  const auto response = localizer::testing::Request(server_->metrics_port(), "GET", "/sessions");
  ASSERT_EQ(response.status, 200);
  const nlohmann::json doc = nlohmann::json::parse(response.body);
  ASSERT_EQ(doc.at("sessions").size(), 1u);
  const auto& session = doc.at("sessions")[0];
  EXPECT_EQ(session.at("kind"), "detections");
  EXPECT_EQ(session.at("frames"), frames_.size());
  // Scans count as activity: idle since the last one, not since the open.
  EXPECT_LT(session.at("idle_s").get<double>(), session.at("age_s").get<double>());
  const v1::TrackList last = Lists(stream).back();
  const auto& targets = session.at("targets");
  ASSERT_EQ(targets.size(), static_cast<size_t>(last.tracks_size()));
  for (int i = 0; i < last.tracks_size(); ++i) {
    EXPECT_EQ(targets[i].at("id"), last.tracks(i).id());
    EXPECT_DOUBLE_EQ(targets[i].at("position_m")[0].get<double>(), last.tracks(i).position_m().x());
    EXPECT_EQ(targets[i].at("status"), last.tracks(i).status() == v1::TRACK_STATUS_TENTATIVE   ? "tentative"
                                       : last.tracks(i).status() == v1::TRACK_STATUS_CONFIRMED ? "confirmed"
                                                                                               : "coasting");
  }
  ASSERT_TRUE(stream.Close().ok());
}

TEST_F(DetectionServiceTest, BadScanIsRefusedInBandAndChangesNothing) {
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(OpenDetections()));
  for (size_t k = 0; k < frames_.size(); ++k) {
    if (k == 4) {
      v1::TrackRequest bad = ScanRequest(frames_[k].scan, 999);
      bad.mutable_scan()->mutable_detections(2)->set_range_m(-3.0);
      ASSERT_TRUE(stream.Send(bad));
      v1::TrackRequest late = ScanRequest(frames_[k - 2].scan, 998);  // time before the last scan's
      ASSERT_TRUE(stream.Send(late));
    }
    ASSERT_TRUE(stream.Send(ScanRequest(frames_[k].scan, k)));
  }
  ASSERT_TRUE(stream.Close().ok());
  std::vector<v1::BlockRejected> rejected;
  for (const auto& r : stream.responses()) {
    if (r.has_rejected()) rejected.push_back(r.rejected());
  }
  ASSERT_EQ(rejected.size(), 2u);
  EXPECT_EQ(rejected[0].request(), "scan");
  EXPECT_EQ(rejected[0].reason(), "scan");
  EXPECT_EQ(rejected[0].code(), "INVALID_ARGUMENT");
  EXPECT_EQ(rejected[0].sequence(), 999u);
  EXPECT_NE(rejected[0].message().find("scan.detections[2].range_m"), std::string::npos) << rejected[0].message();
  EXPECT_EQ(rejected[1].sequence(), 998u);
  EXPECT_EQ(rejected[1].code(), "INVALID_ARGUMENT");
  const std::vector<v1::TrackList> got = Lists(stream);
  const std::vector<engine::ScanResult> want = Offline();
  ASSERT_EQ(got.size(), want.size());
  for (size_t k = 0; k < got.size(); ++k) ExpectSameList(want[k], got[k]);
}

TEST_F(DetectionServiceTest, BlocksToADetectionSessionAndScansToAnAudioSessionAreRefused) {
  const Scenario audio = MakeScenario("tetra-water", 1.0, 1, 2048);
  {
    TestStream stream(stub_.get());
    ASSERT_TRUE(stream.Send(OpenDetections()));
    ASSERT_TRUE(stream.Send(audio.BlockRequest(1, 2048)));
    ASSERT_TRUE(stream.Send(ScanRequest(frames_[0].scan, 1)));
    ASSERT_TRUE(stream.Close().ok());
    int rejections = 0;
    for (const auto& r : stream.responses()) {
      if (!r.has_rejected()) continue;
      ++rejections;
      EXPECT_EQ(r.rejected().reason(), "not_samples");
      EXPECT_EQ(r.rejected().code(), "FAILED_PRECONDITION");
    }
    EXPECT_EQ(rejections, 1);
    EXPECT_EQ(Lists(stream).size(), 1u);
  }
  {
    TestStream stream(stub_.get());
    ASSERT_TRUE(stream.Send(audio.OpenRequest()));
    ASSERT_TRUE(stream.Send(ScanRequest(frames_[0].scan, 1)));
    ASSERT_TRUE(stream.Send(audio.BlockRequest(1, 2048)));
    ASSERT_TRUE(stream.Send(audio.BlockRequest(2, 2048)));
    ASSERT_TRUE(stream.Close().ok());
    int rejections = 0;
    for (const auto& r : stream.responses()) {
      if (!r.has_rejected()) continue;
      ++rejections;
      EXPECT_EQ(r.rejected().reason(), "not_detections");
      EXPECT_EQ(r.rejected().request(), "scan");
    }
    EXPECT_EQ(rejections, 1);
    EXPECT_EQ(stream.estimates().size(), 1u);
  }
}

TEST_F(DetectionServiceTest, BadDetectionConfigIsInvalidArgument) {
  v1::TrackRequest open = OpenDetections();
  open.mutable_open()->mutable_detections()->set_dimensions(4);
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(open));
  const grpc::Status status = stream.Close();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("detections"), std::string::npos) << status.error_message();
}

TEST_F(DetectionServiceTest, AdversarialScansAreBoundedAndOversizedOnesRefusedInBand) {
  // The security review's crash: two scans of 8000 co-located plots (N^2 gate pairs, a cubic
  // assignment: bad_alloc under 3.5 GB). Now: both answered, the second with every gate
  // truncated and its cluster matched greedily; a scan above the session's
  // max_plots_per_scan is refused in-band naming the field, and the session goes on.
  v1::TrackRequest open = OpenDetections();
  open.mutable_open()->mutable_detections()->set_max_plots_per_scan(8000);
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(open));
  engine::Scan crowd;
  crowd.detections.assign(8000, {5000.0, 0.25, std::nullopt, std::nullopt});
  for (int k = 0; k < 2; ++k) {
    crowd.time_s = 1.0 + k;
    ASSERT_TRUE(stream.Send(ScanRequest(crowd, k)));
  }
  engine::Scan too_many = crowd;
  too_many.time_s = 3.0;
  too_many.detections.resize(8001, too_many.detections[0]);
  ASSERT_TRUE(stream.Send(ScanRequest(too_many, 2)));
  crowd.time_s = 4.0;
  crowd.detections.resize(10);
  ASSERT_TRUE(stream.Send(ScanRequest(crowd, 3)));
  ASSERT_TRUE(stream.Close().ok());
  const std::vector<v1::TrackList> lists = Lists(stream);
  ASSERT_EQ(lists.size(), 3u);
  EXPECT_EQ(lists[0].initiated(), 8000u);
  EXPECT_EQ(lists[1].truncated_gates(), 8000u);
  EXPECT_GE(lists[1].greedy_clusters(), 1u);
  EXPECT_LE(lists[1].tracks_size(), 10000);  // the server's default max_tracks
  EXPECT_EQ(lists[2].sequence(), 3u);
  int rejections = 0;
  for (const auto& r : stream.responses()) {
    if (!r.has_rejected()) continue;
    ++rejections;
    EXPECT_EQ(r.rejected().sequence(), 2u);
    EXPECT_EQ(r.rejected().code(), "INVALID_ARGUMENT");
    EXPECT_NE(r.rejected().message().find("max_plots_per_scan"), std::string::npos) << r.rejected().message();
  }
  EXPECT_EQ(rejections, 1);
}

TEST_F(DetectionServiceTest, MaxTracksAboveTheServersLimitIsRefusedNamingTheFlag) {
  v1::TrackRequest open = OpenDetections();
  open.mutable_open()->mutable_detections()->set_max_tracks(10001);
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(open));
  const grpc::Status status = stream.Close();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("--max-tracks"), std::string::npos) << status.error_message();
}

TEST(ScanWire, MaxTrackListBytesBoundsEveryListAndTheServerRefusesALimitThatCannotBeSent) {
  // Random tracks, with the widest values mixed in: the encoded response never exceeds the
  // bound, and the bound is tight for the widest (within the per-message framing).
  std::mt19937_64 engine(17);
  std::uniform_real_distribution<double> value(-1e6, 1e6);
  engine::ScanResult result;
  result.scan_index = 123456;
  result.time_s = 12.5;
  for (int i = 0; i < 500; ++i) {
    engine::tws::TrackReport t;
    t.id = i % 7 == 0 ? UINT64_MAX : static_cast<uint64_t>(i + 1);
    t.status = engine::tws::TrackStatus::kConfirmed;
    t.position_m = Eigen::Vector3d(value(engine), value(engine), value(engine));
    t.velocity_mps = Eigen::Vector3d(value(engine), value(engine), 0.0);
    for (int k = 0; k < 36; ++k) t.covariance(k / 6, k % 6) = value(engine);
    t.hits = i % 3 == 0 ? INT32_MAX : i;
    result.tracks.push_back(t);
  }
  v1::TrackResponse response;
  wire::TrackListToProto(result, UINT64_MAX, response.mutable_tracks());
  response.mutable_tracks()->set_total_s(0.25);
  const int64_t bound = wire::MaxTrackListBytes(500);
  EXPECT_LE(static_cast<int64_t>(response.ByteSizeLong()), bound);
  EXPECT_GT(static_cast<int64_t>(response.ByteSizeLong()), bound * 8 / 10);  // not a loose guess
  ServerOptions options;
  options.max_message_bytes = 1 << 20;  // 1 MiB holds ~2800 tracks, not 10000
  const Status invalid = options.Validate();
  EXPECT_EQ(invalid.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(invalid.message().find("max_tracks"), std::string::npos) << invalid.message();
  options.max_tracks = 2000;
  EXPECT_TRUE(options.Validate().ok());
}

TEST(ScanWire, DecodeValidatesEveryPlotAndRoundTrips) {
  engine::Scan scan;
  scan.time_s = 3.5;
  scan.sensor_position_m = Eigen::Vector3d(1.0, 2.0, 3.0);
  scan.detections.push_back({1000.0, 0.5, std::nullopt, 12.0});
  scan.detections.push_back({2000.0, -3.0, 0.1, std::nullopt});
  v1::Scan p;
  wire::EncodeScan(scan, 4, &p);
  auto back = wire::DecodeScan(p);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  ASSERT_EQ(back->detections.size(), 2u);
  EXPECT_EQ(*back->detections[0].snr_db, 12.0);
  EXPECT_FALSE(back->detections[0].elevation_rad.has_value());
  EXPECT_EQ(*back->detections[1].elevation_rad, 0.1);
  EXPECT_EQ(back->sensor_position_m, scan.sensor_position_m);
  const auto field_of = [&](auto mutate) {
    v1::Scan bad = p;
    mutate(bad);
    return wire::DecodeScan(bad).status().message();
  };
  EXPECT_NE(
      field_of([](v1::Scan& s) { s.mutable_detections(1)->set_bearing_rad(4.0); }).find("detections[1].bearing_rad"),
      std::string::npos);
  EXPECT_NE(
      field_of([](v1::Scan& s) { s.mutable_detections(0)->set_range_m(std::nan("")); }).find("detections[0].range_m"),
      std::string::npos);
  EXPECT_NE(field_of([](v1::Scan& s) { s.mutable_detections(1)->set_elevation_rad(2.0); }).find("elevation_rad"),
            std::string::npos);
  EXPECT_NE(field_of([](v1::Scan& s) { s.set_time_s(INFINITY); }).find("scan.time_s"), std::string::npos);
}

}  // namespace
}  // namespace localizer::server::testing
