// The live web view's data: the per-session track ring (bounded, oldest first, only
// initialised fixes) and GET /sessions after real traffic (valid JSON of the documented
// shape, holding the estimates the stream received; client labels escaped), and GET /
// serving the self-contained page; ended sessions kept for the live view (bounded in number
// and time, with their tracks).
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "server/service/finished_sessions.h"
#include "server/service/sessions_json.h"
#include "server/service/track_history.h"
#include "tests/server/http_client.h"
#include "tests/server/service_fixture.h"
#include "wire/block_wire.h"
#include "wire/config_wire.h"

namespace localizer::server::testing {
namespace {

constexpr int64_t kBlock = 2048;

engine::Estimate Fix(uint64_t frame, double x) {
  engine::Estimate e;
  e.frame_index = frame;
  e.t_s = 0.1 * static_cast<double>(frame);
  e.initialised = true;
  e.state << x, 2.0 * x, -x, 1.0, 0.0, 0.0;
  e.covariance = engine::Mat6::Identity() * 4.0;
  return e;
}

TEST(TrackHistoryTest, KeepsTheLastCapacityFixesOldestFirst) {
  TrackHistory track(5);
  for (uint64_t k = 0; k < 12; ++k) track.Append(Fix(k, static_cast<double>(k)));
  const TrackSnapshot s = track.Snapshot();
  EXPECT_EQ(s.capacity, 5u);
  EXPECT_EQ(s.frames, 12u);
  ASSERT_EQ(s.points.size(), 5u);
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(s.points[i].frame_index, 7 + i);
    EXPECT_DOUBLE_EQ(s.points[i].position_m[0], static_cast<double>(7 + i));
    EXPECT_DOUBLE_EQ(s.points[i].position_m[1], 2.0 * static_cast<double>(7 + i));
    EXPECT_DOUBLE_EQ(s.points[i].position_std_m[2], 2.0);
  }
}

TEST(TrackHistoryTest, CountsFramesWithoutAFixButStoresNoPosition) {
  TrackHistory track(4);
  engine::Estimate before;  // not initialised
  before.model_probabilities = {{"cv", 1.0}};
  track.Append(before);
  track.Append(before);
  engine::Estimate fix = Fix(2, 3.0);
  fix.model_probabilities = {{"cv", 0.25}, {"ct", 0.75}};
  track.Append(fix);
  const TrackSnapshot s = track.Snapshot();
  EXPECT_EQ(s.frames, 3u);
  EXPECT_EQ(s.initialised_frames, 1u);
  ASSERT_EQ(s.points.size(), 1u);
  EXPECT_EQ(s.points[0].frame_index, 2u);
  ASSERT_EQ(s.model_probabilities.size(), 2u);  // the latest estimate's
  EXPECT_EQ(s.model_probabilities[1].model, "ct");
}

TEST(TrackHistoryTest, KeepsTheLatestPresenceAndAmbiguity) {
  TrackHistory track(4);
  EXPECT_FALSE(track.Snapshot().presence.has_value());  // no frame yet
  engine::Estimate heard = Fix(0, 1.0);
  heard.source_present = true;
  heard.presence_statistic = 20.0;
  heard.presence_threshold = 5.0;
  heard.ambiguous = true;
  heard.modes = 2;
  heard.far_field = true;
  heard.range_sd_m = 12.5;
  track.Append(heard);
  engine::Estimate silent = Fix(1, 1.1);  // the tracker coasts: a prediction
  silent.presence_statistic = 2.0;
  silent.presence_threshold = 5.0;
  silent.modes = 1;
  silent.range_sd_m = 0.5;
  track.Append(silent);
  const TrackSnapshot s = track.Snapshot();
  ASSERT_TRUE(s.presence.has_value());
  EXPECT_TRUE(s.presence->tested);
  EXPECT_FALSE(s.presence->present);
  EXPECT_EQ(s.presence->statistic, 2.0);
  EXPECT_EQ(s.presence->threshold, 5.0);
  EXPECT_FALSE(s.presence->ambiguous);
  EXPECT_EQ(s.presence->modes, 1);
  EXPECT_FALSE(s.presence->far_field);
  EXPECT_EQ(s.presence->range_sd_m, 0.5);
  EXPECT_EQ(s.present_frames, 1u);
  ASSERT_EQ(s.points.size(), 2u);
  EXPECT_TRUE(s.points[0].source_present);
  EXPECT_TRUE(s.points[0].ambiguous);
  EXPECT_TRUE(s.points[0].far_field);
  EXPECT_FALSE(s.points[1].source_present);
  EXPECT_FALSE(s.points[1].far_field);
}

// Direction sessions: every (frame, source) direction in a ring of kSourcesPerFrame x
// capacity, oldest first, and the latest frame's sources; a frame without sources clears
// them. Position sessions keep none.
TEST(TrackHistoryTest, KeepsDirectionsPerSourceAndTheLatestSources) {
  TrackHistory track(2);  // room for 2 x 4 = 8 directions
  for (uint64_t frame = 0; frame < 5; ++frame) {
    engine::Estimate e;
    e.frame_index = frame;
    e.t_s = 0.1 * static_cast<double>(frame);
    for (uint64_t id = 1; id <= 2; ++id) {
      engine::SourceEstimate s;
      s.source_id = id;
      s.azimuth_rad = 0.1 * static_cast<double>(id) + 0.01 * static_cast<double>(frame);
      s.elevation_rad = 0.2;
      s.source_present = id == 1;
      e.sources.push_back(s);
    }
    track.Append(e);
  }
  TrackSnapshot s = track.Snapshot();
  ASSERT_EQ(s.directions.size(), 8u);  // frames 1..4, two sources each
  EXPECT_EQ(s.directions.front().frame_index, 1u);
  EXPECT_EQ(s.directions.back().frame_index, 4u);
  EXPECT_EQ(s.directions.back().source_id, 2u);
  EXPECT_DOUBLE_EQ(s.directions.back().azimuth_rad, 0.24);
  for (size_t i = 1; i < s.directions.size(); ++i) EXPECT_GE(s.directions[i].t_s, s.directions[i - 1].t_s);
  ASSERT_EQ(s.sources.size(), 2u);
  EXPECT_TRUE(s.sources[0].source_present);
  EXPECT_FALSE(s.sources[1].source_present);
  EXPECT_TRUE(s.points.empty());     // no position
  track.Append(engine::Estimate{});  // a frame with no source
  s = track.Snapshot();
  EXPECT_TRUE(s.sources.empty());
  EXPECT_EQ(s.directions.size(), 8u);
}

TEST(SessionsJsonTest, NoSessionsIsAnEmptyList) {
  const auto doc = nlohmann::json::parse(SessionsJson({}, Clock::now(), 60.0));
  EXPECT_EQ(doc.at("sessions_total"), 0);
  EXPECT_TRUE(doc.at("sessions").is_array());
  EXPECT_TRUE(doc.at("sessions").empty());
  EXPECT_TRUE(doc.at("finished").is_array());
  EXPECT_TRUE(doc.at("finished").empty());
}

FinishedSession Ended(int n, Clock::time_point at) {
  return {"{\"id\":\"s" + std::to_string(n) + "\"}", n % 2 ? "finished" : "expired", at};
}

TEST(FinishedSessionsTest, KeepsTheLastKeepForKeepSecondsMostRecentFirst) {
  const Clock::time_point t0 = Clock::now();
  FinishedSessions kept(3, 10.0);
  for (int n = 1; n <= 5; ++n) kept.Add(Ended(n, t0 + std::chrono::seconds(n)));
  std::vector<FinishedSession> now = kept.Snapshot(t0 + std::chrono::seconds(6));
  ASSERT_EQ(now.size(), 3u);  // the two oldest went to make room
  EXPECT_EQ(now[0].session_json, "{\"id\":\"s5\"}");
  EXPECT_EQ(now[2].session_json, "{\"id\":\"s3\"}");
  // s3 ended at 3 s: gone after 13 s; s4 and s5 stay until 14 s and 15 s.
  now = kept.Snapshot(t0 + std::chrono::milliseconds(13500));
  ASSERT_EQ(now.size(), 2u);
  EXPECT_EQ(now[1].session_json, "{\"id\":\"s4\"}");
  EXPECT_TRUE(kept.Snapshot(t0 + std::chrono::seconds(16)).empty());
  // The document carries them after the live ones, as valid JSON.
  const Clock::time_point t = t0 + std::chrono::seconds(7);
  const auto doc = nlohmann::json::parse(SessionsJson({}, t, 60.0, {Ended(7, t0), Ended(8, t0)}));
  ASSERT_EQ(doc.at("finished").size(), 2u);
  EXPECT_EQ(doc.at("finished")[0].at("session").at("id"), "s7");
  EXPECT_EQ(doc.at("finished")[1].at("reason"), "expired");
  EXPECT_DOUBLE_EQ(doc.at("finished")[0].at("finished_ago_s").get<double>(), 7.0);
}

TEST(FinishedSessionsTest, KeepZeroKeepsNothing) {
  FinishedSessions none(0, 600.0);
  EXPECT_FALSE(none.enabled());
  none.Add(Ended(1, Clock::now()));
  EXPECT_TRUE(none.Snapshot(Clock::now()).empty());
  FinishedSessions capped(100000, 600.0);
  for (int n = 0; n < 300; ++n) capped.Add(Ended(n, Clock::now()));
  EXPECT_EQ(capped.Snapshot(Clock::now()).size(), FinishedSessions::kMaxKeep);
}

TEST_F(ServiceTest, SessionsJsonListsTheStreamedTrack) {
  const Scenario s = MakeScenario("tetra-water", 3.0, 1, kBlock, 512);
  TestStream stream(stub_.get());
  v1::TrackRequest open = s.OpenRequest();
  // A label a client may send: quotes, a backslash, markup, a control character.
  const std::string label = "tank \"A\"\\ <b>\x01";
  open.mutable_open()->set_label(label);
  ASSERT_TRUE(stream.Send(open));
  const int64_t blocks = s.BlockCount(kBlock);
  for (int64_t k = 1; k <= blocks; ++k) ASSERT_TRUE(stream.Send(s.BlockRequest(k, kBlock)));
  ASSERT_TRUE(stream.WaitForEstimates(s.offline.size()));

  const auto response = localizer::testing::Request(server_->metrics_port(), "GET", "/sessions");
  ASSERT_EQ(response.status, 200);
  EXPECT_EQ(response.headers.at("content-type"), "application/json; charset=utf-8");
  nlohmann::json doc;
  ASSERT_NO_THROW(doc = nlohmann::json::parse(response.body)) << response.body.substr(0, 400);
  ASSERT_EQ(doc.at("sessions").size(), 1u);
  const auto& session = doc.at("sessions")[0];
  EXPECT_EQ(session.at("id"), stream.opened().session_id());
  EXPECT_EQ(session.at("label"), label);
  EXPECT_EQ(session.at("backend"), "cpu");
  EXPECT_EQ(session.at("filter_type"), engine::FilterKindName(s.config.tracker.kind));
  EXPECT_EQ(session.at("frames"), s.offline.size());
  ASSERT_EQ(session.at("sensors_m").size(), s.config.sensors_m.size());
  EXPECT_DOUBLE_EQ(session.at("sensors_m")[1][0].get<double>(), s.config.sensors_m[1].x());

  std::vector<v1::Estimate> fixes;
  for (const auto& e : stream.estimates()) {
    if (e.initialised()) fixes.push_back(e);
  }
  ASSERT_FALSE(fixes.empty());
  const auto& track = session.at("track");
  ASSERT_EQ(track.size(), std::min<size_t>(fixes.size(), session.at("track_capacity").get<size_t>()));
  const v1::Estimate& last = fixes.back();
  const auto& point = track.back();
  EXPECT_EQ(point.at("frame"), last.frame_index());
  EXPECT_DOUBLE_EQ(point.at("t_s").get<double>(), last.t_s());
  EXPECT_DOUBLE_EQ(point.at("position_m")[0].get<double>(), last.position_m().x());
  EXPECT_DOUBLE_EQ(point.at("position_m")[2].get<double>(), last.position_m().z());
  EXPECT_GE(point.at("position_std_m")[0].get<double>(), 0.0);
  for (size_t i = 1; i < track.size(); ++i) EXPECT_GT(track[i].at("t_s"), track[i - 1].at("t_s"));
  EXPECT_EQ(point.at("source_present").get<bool>(), last.source_present());
  EXPECT_EQ(point.at("ambiguous").get<bool>(), last.ambiguous());
  EXPECT_EQ(point.at("far_field").get<bool>(), last.far_field());
  // The latest frame's presence and ambiguity, as the stream received them.
  const v1::Estimate latest = stream.estimates().back();  // a copy: estimates() returns a temporary
  const auto& presence = session.at("presence");
  ASSERT_TRUE(presence.is_object()) << session.dump();
  EXPECT_EQ(presence.at("source_present").get<bool>(), latest.source_present());
  EXPECT_EQ(presence.at("ambiguous").get<bool>(), latest.ambiguous());
  EXPECT_EQ(presence.at("modes").get<uint32_t>(), latest.modes());
  EXPECT_EQ(presence.at("far_field").get<bool>(), latest.initialised() && latest.far_field());
  EXPECT_DOUBLE_EQ(presence.at("range_sd_m").get<double>(), latest.range_sd_m());
  EXPECT_DOUBLE_EQ(presence.at("threshold").get<double>(), latest.presence_threshold());
  const std::string state = presence.at("state");
  EXPECT_EQ(state, latest.presence_threshold() <= 0.0 ? "untested" : latest.source_present() ? "present" : "silent");
  uint64_t present = 0;
  for (const auto& e : stream.estimates()) present += e.source_present() ? 1 : 0;
  EXPECT_EQ(session.at("present_frames").get<uint64_t>(), present);
  ASSERT_TRUE(stream.Close().ok());
}

// A direction session (a planar board) on the server: /sessions says what it reports and
// lists its sources' directions. One white source, whole-sample delays of a plane wave
// from azimuth 0.9, elevation 0.4 rad, 20 dB over the sensors' noise.
TEST_F(ServiceTest, SessionsJsonListsADirectionSessionsSources) {
  constexpr double kFs = 16000.0, kC = 343.0;
  const std::vector<engine::Vec3> board = {{0.3, 0, 0}, {0, 0.3, 0}, {-0.3, 0, 0}, {0, -0.3, 0}};
  const engine::Vec3 u(std::cos(0.4) * std::cos(0.9), std::cos(0.4) * std::sin(0.9), std::sin(0.4));
  engine::AudioSessionConfig config;
  config.sensors_m = board;
  config.sound_speed_mps = kC;
  config.sample_rate_hz = kFs;
  config.frame_samples = 1024;
  config.hop_samples = 512;
  config.source_side = engine::Vec3::UnitZ();
  v1::TrackRequest open;
  *open.mutable_open() = wire::ConfigToProto(config, "board");
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(open));
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  constexpr int kSamples = 16000, kPad = 64;
  std::vector<double> source(kSamples + 2 * kPad);
  for (double& v : source) v = normal(rng);
  std::vector<float> samples(board.size() * kSamples);  // channel-major
  for (size_t m = 0; m < board.size(); ++m) {
    const auto delay = static_cast<int>(std::lround(-board[m].dot(u) / kC * kFs));
    for (int i = 0; i < kSamples; ++i)
      samples[m * kSamples + i] = static_cast<float>(source[static_cast<size_t>(kPad + i - delay)] + 0.1 * normal(rng));
  }
  v1::TrackRequest block;
  wire::EncodeBlock({1, static_cast<int>(board.size()), kSamples, samples.data()}, false, block.mutable_block());
  ASSERT_TRUE(stream.Send(block));
  const size_t frames = (kSamples - 1024) / 512 + 1;
  ASSERT_TRUE(stream.WaitForEstimates(frames));
  EXPECT_EQ(stream.opened().localization(), "direction");
  EXPECT_EQ(stream.opened().array_shape(), "planar");

  const auto response = localizer::testing::Request(server_->metrics_port(), "GET", "/sessions");
  ASSERT_EQ(response.status, 200);
  const nlohmann::json doc = nlohmann::json::parse(response.body);
  const auto& session = doc.at("sessions")[0];
  EXPECT_EQ(session.at("localization"), "direction");
  EXPECT_EQ(session.at("array_shape"), "planar");
  EXPECT_TRUE(session.at("track").empty());  // no positions
  ASSERT_EQ(session.at("sources").size(), 1u) << session.dump();
  const auto& now = session.at("sources")[0];
  EXPECT_NEAR(now.at("azimuth_rad").get<double>(), 0.9, 0.1);
  EXPECT_TRUE(now.at("cone_angle_rad").is_null());  // NaN: not a line
  const auto& directions = session.at("directions");
  ASSERT_FALSE(directions.empty());
  EXPECT_EQ(directions.back().at("id"), now.at("id"));
  EXPECT_EQ(directions.back().at("frame").get<uint64_t>(), frames - 1);
  ASSERT_TRUE(stream.Close().ok());
}

// A session streams its scene and half-closes: the stream ends OK, the session leaves the
// registry, and GET /sessions lists it under "finished" with the track the stream received.
TEST_F(ServiceTest, AnEndedSessionStaysInTheLiveViewWithItsTrack) {
  const Scenario s = MakeScenario("tetra-water", 3.0, 1, kBlock, 512);
  TestStream stream(stub_.get());
  v1::TrackRequest open = s.OpenRequest();
  open.mutable_open()->set_label("quick run");
  ASSERT_TRUE(stream.Send(open));
  for (int64_t k = 1; k <= s.BlockCount(kBlock); ++k) ASSERT_TRUE(stream.Send(s.BlockRequest(k, kBlock)));
  ASSERT_TRUE(stream.Close().ok());
  std::vector<v1::Estimate> fixes;
  for (const auto& e : stream.estimates()) {
    if (e.initialised()) fixes.push_back(e);
  }
  ASSERT_FALSE(fixes.empty());

  const auto response = localizer::testing::Request(server_->metrics_port(), "GET", "/sessions");
  ASSERT_EQ(response.status, 200);
  nlohmann::json doc;
  ASSERT_NO_THROW(doc = nlohmann::json::parse(response.body)) << response.body.substr(0, 400);
  EXPECT_TRUE(doc.at("sessions").empty());
  ASSERT_EQ(doc.at("finished").size(), 1u);
  const auto& ended = doc.at("finished")[0];
  EXPECT_EQ(ended.at("reason"), "finished");
  EXPECT_GE(ended.at("finished_ago_s").get<double>(), 0.0);
  const auto& session = ended.at("session");
  EXPECT_EQ(session.at("id"), stream.opened().session_id());
  EXPECT_EQ(session.at("label"), "quick run");
  EXPECT_EQ(session.at("frames"), s.offline.size());
  EXPECT_EQ(session.at("blocks"), s.BlockCount(kBlock));
  const auto& track = session.at("track");
  ASSERT_EQ(track.size(), std::min<size_t>(fixes.size(), session.at("track_capacity").get<size_t>()));
  EXPECT_EQ(track.back().at("frame"), fixes.back().frame_index());
  EXPECT_DOUBLE_EQ(track.back().at("position_m")[0].get<double>(), fixes.back().position_m().x());
}

TEST_F(ServiceTest, ALiveViewKeepingNoEndedSessionListsNone) {
  server_->Shutdown();
  ServerOptions options;
  options.live_keep_finished = 0;
  StartServer(options);
  const Scenario s = MakeScenario("tetra-water", 1.0, 1, kBlock, 512);
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(s.OpenRequest()));
  for (int64_t k = 1; k <= s.BlockCount(kBlock); ++k) ASSERT_TRUE(stream.Send(s.BlockRequest(k, kBlock)));
  ASSERT_TRUE(stream.Close().ok());
  const auto doc = nlohmann::json::parse(localizer::testing::Request(server_->metrics_port(), "GET", "/sessions").body);
  EXPECT_TRUE(doc.at("sessions").empty());
  EXPECT_TRUE(doc.at("finished").empty());
}

TEST_F(ServiceTest, RootServesTheSelfContainedLivePage) {
  const auto response = localizer::testing::Request(server_->metrics_port(), "GET", "/");
  ASSERT_EQ(response.status, 200);
  EXPECT_EQ(response.headers.at("content-type"), "text/html; charset=utf-8");
  EXPECT_NE(response.body.find("fetch(\"/sessions\""), std::string::npos);
  EXPECT_NE(response.body.find("<a href=\"/metrics\">"), std::string::npos);
  EXPECT_NE(response.body.find("s.presence"), std::string::npos);  // presence and ambiguity shown
  EXPECT_NE(response.body.find("ambiguous"), std::string::npos);
  EXPECT_NE(response.body.find("drawDirectionMap(c.xz, s.sources"), std::string::npos);  // direction sessions
  EXPECT_NE(response.body.find("doc.finished"), std::string::npos);                      // ended sessions
  EXPECT_NE(response.body.find("\"replay\""), std::string::npos);
  // Self-contained: nothing loaded from another origin.
  EXPECT_EQ(response.body.find("src="), std::string::npos);
  EXPECT_EQ(response.body.find("https://"), std::string::npos);
  EXPECT_EQ(localizer::testing::Request(server_->metrics_port(), "GET", "/metrics").status, 200);
}

}  // namespace
}  // namespace localizer::server::testing
