// The C++ client (clients/grpc) and the CLI's server paths against an in-process
// localizer-server on a loopback port.
//
// (a) `track --server` (client::RunRemoteTrack, the function the command calls) gives the
//     same estimates as offline `track` (io::RunTrack) bit for bit: both build the config
//     with io::PrepareTrack, the config travels with every field explicit, and the server
//     runs the same engine on the cpu backend. Only the stage timings differ. The CSVs are
//     equal column by column except tdoa_ms and filter_ms.
// (b) A server nobody listens on: UNAVAILABLE, and the CLI exits 1.
// Locate and the server's config validation: locate_service_test.cc.
// Tests marked "CLI" run the localizer-cli executable (LOCALIZER_CLI_BIN) and are skipped
// when the build does not pass its path.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "clients/grpc/connection.h"
#include "clients/grpc/latency_summary.h"
#include "clients/grpc/remote_track.h"
#include "clients/grpc/streamer.h"
#include "clients/grpc/track_stream.h"
#include "clients/io/array_json.h"
#include "clients/io/simulation_files.h"
#include "clients/io/track_runner.h"
#include "engine/core/version.h"
#include "localizer/v1/localizer.grpc.pb.h"
#include "server/service/server.h"
#include "tests/clients/test_util.h"
#include "tests/pipeline/scenario_run.h"
#include "tests/server/loopback_server.h"
#include "tests/server/run_shell.h"
#include "wire/config_wire.h"
#include "wire/status_wire.h"

namespace localizer::client {
namespace {

using io::testing::TempDir;

// A loopback port nobody listens on: bound, read back and released.
int UnusedPort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  socklen_t length = sizeof(address);
  if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    if (fd >= 0) ::close(fd);
    return 1;  // port 1 is privileged: nothing listens there either
  }
  ::close(fd);
  return ntohs(address.sin_port);
}

// Every line of a CSV, with the named columns removed.
std::vector<std::string> CsvWithout(const std::string& path, const std::vector<std::string>& drop) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  std::vector<bool> keep;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream split(line);
    for (std::string field; std::getline(split, field, ',');) fields.push_back(field);
    if (keep.empty()) {
      for (const std::string& name : fields) {
        keep.push_back(std::find(drop.begin(), drop.end(), name) == drop.end());
      }
    }
    std::string kept;
    for (size_t i = 0; i < fields.size(); ++i) {
      if (i < keep.size() && keep[i]) kept += fields[i] + ",";
    }
    lines.push_back(kept);
  }
  return lines;
}

// Every number the engine computed, compared exactly; the stage timings are not.
void ExpectBitIdentical(const engine::Estimate& want, const engine::Estimate& got) {
  EXPECT_EQ(got.frame_index, want.frame_index);
  EXPECT_EQ(got.sequence, want.sequence) << "frame " << want.frame_index;
  EXPECT_EQ(got.t_s, want.t_s) << "frame " << want.frame_index;
  EXPECT_EQ(got.initialised, want.initialised);
  EXPECT_EQ(got.reinitialised, want.reinitialised);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(got.state(i), want.state(i)) << "frame " << want.frame_index;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) EXPECT_EQ(got.covariance(r, c), want.covariance(r, c));
  }
  EXPECT_EQ(got.ess, want.ess);
  EXPECT_EQ(got.tdoa_sigma_s, want.tdoa_sigma_s);
  EXPECT_EQ(got.pairs_used, want.pairs_used);
  EXPECT_EQ(got.nis, want.nis);
  EXPECT_EQ(got.delay_s, want.delay_s);
  EXPECT_EQ(got.quality, want.quality);
  EXPECT_EQ(got.source_present, want.source_present) << "frame " << want.frame_index;
  EXPECT_EQ(got.presence_statistic, want.presence_statistic);
  EXPECT_EQ(got.presence_threshold, want.presence_threshold);
  EXPECT_EQ(got.ambiguous, want.ambiguous);
  EXPECT_EQ(got.modes, want.modes);
}

class CliStreamTest : public LoopbackServerTest {
 protected:
  // tetra-water for `duration_s` written as the files `simulate --out` writes.
  io::SimulationFiles SimulateToFiles(const TempDir& dir, double duration_s) {
    auto run = io::SimulateScenario("tetra-water", 1, duration_s);
    EXPECT_TRUE(run.ok()) << run.status().ToString();
    auto files = io::WriteSimulationFiles(dir.File("sim"), *run);
    EXPECT_TRUE(files.ok()) << files.status().ToString();
    return *files;
  }

  // The job `track --array A --wav W --out OUT` builds with default flags (cmd_track.cc:
  // io::TrackConfigFor on engine::AudioSessionConfig's defaults).
  static io::TrackJob TrackJobFor(const io::SimulationFiles& files, const std::string& out) {
    auto array = io::ReadArrayFile(files.array_path);
    EXPECT_TRUE(array.ok()) << array.status().ToString();
    io::TrackJob job;
    job.wav_paths = {files.wav_path};
    job.array_source = files.array_path;
    job.array_sample_rate_hz = array->sample_rate_hz;
    job.config = io::TrackConfigFor(engine::AudioSessionConfig{}, *array, {}, array->sample_rate_hz.value_or(0.0));
    job.estimates_path = out;
    return job;
  }
};

// (a) The same seed gives the same numbers through the server as offline.
TEST_F(CliStreamTest, TrackOverServerIsBitIdenticalToOffline) {
  TempDir dir;
  const io::SimulationFiles files = SimulateToFiles(dir, 4.0);
  constexpr int64_t kBlockSamples = 4096;
  const double sample_rate_hz = 11025.0;

  // Offline in blocks of exactly kBlockSamples, so that Estimate.sequence matches too.
  io::TrackJob job = TrackJobFor(files, dir.File("offline.csv"));
  job.block_s = static_cast<double>(kBlockSamples) / sample_rate_hz;
  std::vector<engine::Estimate> offline;
  io::TrackCallbacks collect;
  collect.on_estimate = [&offline](const engine::Estimate& e) { offline.push_back(e); };
  auto summary = io::RunTrack(job, collect);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  ASSERT_GT(offline.size(), 15u);

  io::TrackJob remote_job = job;
  remote_job.estimates_path = dir.File("server.csv");
  RemoteTrackOptions options;
  options.block_samples = kBlockSamples;
  options.label = "cli_stream_test";
  auto remote = RunRemoteTrack(channel_, remote_job, options);
  ASSERT_TRUE(remote.ok()) << remote->stream.status().ToString();
  ASSERT_TRUE(remote->stream.status().ok()) << remote->stream.status().ToString();
  EXPECT_EQ(remote->opened.backend(), "cpu");
  EXPECT_TRUE(remote->stream.rejections.empty());
  EXPECT_TRUE(remote->stream.gaps.empty());
  EXPECT_EQ(remote->stream.samples_sent_per_channel, summary->samples_per_channel);

  const std::vector<engine::Estimate> streamed = remote->stream.Estimates();
  ASSERT_EQ(streamed.size(), offline.size());
  for (size_t i = 0; i < offline.size(); ++i) ExpectBitIdentical(offline[i], streamed[i]);
  for (const double latency_s : remote->stream.ClientLatencies()) {
    EXPECT_TRUE(std::isfinite(latency_s) && latency_s >= 0.0);
  }

  // The CSVs: equal except the stage wall times. Offline in its default 0.25 s blocks
  // too: framing does not depend on how the samples were cut into blocks.
  const std::vector<std::string> timing_columns = {"tdoa_ms", "filter_ms"};
  const auto server_csv = CsvWithout(dir.File("server.csv"), timing_columns);
  EXPECT_EQ(server_csv, CsvWithout(dir.File("offline.csv"), timing_columns));
  io::TrackJob default_blocks = TrackJobFor(files, dir.File("offline_default.csv"));
  ASSERT_TRUE(io::RunTrack(default_blocks).ok());
  EXPECT_EQ(server_csv, CsvWithout(dir.File("offline_default.csv"), timing_columns));
}

// Real-time pacing: block k leaves once its audio would have been recorded, so the stream
// cannot end before the audio's duration has elapsed. 16-bit PCM still tracks.
TEST_F(CliStreamTest, RealtimePacingWithPcm16) {
  auto run = io::SimulateScenario("tetra-water", 2, 1.5);
  ASSERT_TRUE(run.ok()) << run.status().ToString();
  const engine::SimResult& sim = run->result;
  engine::AudioSessionConfig config = engine::SessionConfigFor(run->scenario);
  config.tracker.particle.particles = 1024;
  auto stream = OpenTrackSession(channel_, config, "realtime", "");
  ASSERT_TRUE(stream.ok()) << stream.status().ToString();
  EXPECT_FALSE((*stream)->session_key().empty());

  StreamOptions options;
  options.channel_count = sim.channel_count;
  options.sample_rate_hz = sim.sample_rate_hz;
  options.block_samples = 1024;
  options.pacing = Pacing::kRealtime;
  options.encoding = Encoding::kPcm16;
  int seen = 0;
  StreamCallbacks callbacks;
  callbacks.on_estimate = [&seen](const StreamedEstimate&) { ++seen; };
  const StreamResult result = StreamBlocks(
      **stream, ChannelMajorSource(sim.samples.data(), sim.channel_count, sim.samples_per_channel), options, callbacks);
  ASSERT_TRUE(result.status().ok()) << result.status().ToString();
  const double audio_s = static_cast<double>(sim.samples_per_channel) / sim.sample_rate_hz;
  EXPECT_EQ(result.samples_sent_per_channel, sim.samples_per_channel);
  EXPECT_EQ(result.blocks_sent, static_cast<uint64_t>((sim.samples_per_channel + 1023) / 1024));
  EXPECT_GE(result.wall_s, audio_s);
  // Frames of 4096 samples every 2048: floor((N - 4096) / 2048) + 1.
  EXPECT_EQ(result.estimates.size(), static_cast<size_t>((sim.samples_per_channel - 4096) / 2048 + 1));
  EXPECT_EQ(seen, static_cast<int>(result.estimates.size()));
  const LatencySummary latency = SummariseLatencies(result.ClientLatencies());
  EXPECT_EQ(latency.count, static_cast<int64_t>(result.estimates.size()));
  EXPECT_EQ(latency.unknown, 0);
  EXPECT_LE(latency.p50_s, latency.p95_s);
  EXPECT_LE(latency.p95_s, latency.p99_s);
}

// (b) Nobody listening: UNAVAILABLE with gRPC's own message, before any file is written.
TEST_F(CliStreamTest, UnreachableServerIsUnavailable) {
  TempDir dir;
  const io::SimulationFiles files = SimulateToFiles(dir, 1.0);
  const std::string nowhere = "127.0.0.1:" + std::to_string(UnusedPort());
  auto remote = RunRemoteTrack(Connect(nowhere), TrackJobFor(files, dir.File("est.csv")), {});
  ASSERT_FALSE(remote.ok());
  EXPECT_EQ(remote.status().code(), StatusCode::kUnavailable);
  EXPECT_EQ(remote.status().message().rfind("UNAVAILABLE: ", 0), 0u) << remote.status().message();

  const Status waited = WaitConnected(Connect(nowhere), 0.2);
  EXPECT_EQ(waited.code(), StatusCode::kUnavailable);
  EXPECT_EQ(waited.message().rfind("UNAVAILABLE: ", 0), 0u) << waited.message();
}

#ifdef LOCALIZER_CLI_BIN
// Runs the CLI with `args`; returns its exit code and what it wrote to stderr.
std::pair<int, std::string> RunCli(const std::string& args, const TempDir& dir) {
  const std::string err = dir.File("stderr.txt");
  const std::string command =
      std::string(LOCALIZER_CLI_BIN) + " " + args + " > " + dir.File("stdout.txt") + " 2> " + err;
  const int status = localizer::testing::RunShell(command);
  std::ifstream in(err);
  std::stringstream text;
  text << in.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
}
#endif

// (b) CLI: "localizer-cli track: UNAVAILABLE: ...", exit 1 (a runtime error, not usage).
TEST_F(CliStreamTest, CliUnreachableServerExitsOne) {
#ifndef LOCALIZER_CLI_BIN
  GTEST_SKIP() << "LOCALIZER_CLI_BIN not defined by the build";
#else
  TempDir dir;
  const io::SimulationFiles files = SimulateToFiles(dir, 1.0);
  const auto [code, err] = RunCli("track --server 127.0.0.1:" + std::to_string(UnusedPort()) + " --array " +
                                      files.array_path + " --wav " + files.wav_path + " --out " + dir.File("e.csv"),
                                  dir);
  EXPECT_EQ(code, 1) << err;
  EXPECT_EQ(err.rfind("localizer-cli track: UNAVAILABLE: ", 0), 0u) << err;
  const auto [usage_code, usage_err] = RunCli(
      "track --rate max --array " + files.array_path + " --wav " + files.wav_path + " --out " + dir.File("e.csv"), dir);
  EXPECT_EQ(usage_code, 2) << usage_err;  // --rate without --server
#endif
}

// localizer-cli --version prints the build's version (the server's too) and exits 0.
TEST_F(CliStreamTest, CliVersionPrintsTheBuildsVersion) {
#ifndef LOCALIZER_CLI_BIN
  GTEST_SKIP() << "LOCALIZER_CLI_BIN not defined by the build";
#else
  TempDir dir;
  const auto [code, err] = RunCli("--version", dir);
  EXPECT_EQ(code, 0) << err;
  std::ifstream out(dir.File("stdout.txt"));
  std::string line;
  std::getline(out, line);
  EXPECT_EQ(line, std::string("localizer-cli ") + kLocalizerVersion);
#endif
}

// The array file's water column and the presence settings reach the server: the session's
// effective config echoes them (open sides unset), and a bad bound is a usage error naming
// the flag before anything is sent.
TEST_F(CliStreamTest, BoundsAndPresenceSettingsReachTheServer) {
  TempDir dir;
  const io::SimulationFiles files = SimulateToFiles(dir, 1.0);
  io::TrackJob job = TrackJobFor(files, dir.File("bounded.csv"));
  job.config.bounds_max_m.z() = 50.0;   // the surface
  job.config.bounds_min_m.z() = -60.0;  // the bottom
  job.config.presence_false_alarm = 0.02;
  job.config.source_timeout_s = 4.0;
  job.config.search_radius_m = 80.0;
  RemoteTrackOptions options;
  options.block_samples = 4096;
  auto remote = RunRemoteTrack(channel_, job, options);
  ASSERT_TRUE(remote.ok()) << remote.status().ToString();
  ASSERT_TRUE(remote->stream.status().ok()) << remote->stream.status().ToString();
  const v1::SessionConfig& effective = remote->opened.effective_config();
  ASSERT_TRUE(effective.has_bounds());
  EXPECT_EQ(effective.bounds().max_z_m(), 50.0);
  EXPECT_EQ(effective.bounds().min_z_m(), -60.0);
  EXPECT_FALSE(effective.bounds().has_min_x_m());
  EXPECT_FALSE(effective.bounds().has_max_y_m());
  EXPECT_EQ(effective.presence_false_alarm(), 0.02);
  EXPECT_EQ(effective.source_timeout_s(), 4.0);
  EXPECT_EQ(effective.search_radius_m(), 80.0);
#ifdef LOCALIZER_CLI_BIN
  const std::string track = "track --server " + target_ + " --array " + files.array_path + " --wav " + files.wav_path +
                            " --out " + dir.File("e.csv");
  auto [code, err] = RunCli(track + " --bounds-min 0,0,inf", dir);
  EXPECT_EQ(code, 2) << err;
  EXPECT_NE(err.find("--bounds-min"), std::string::npos) << err;
  std::tie(code, err) = RunCli(track + " --surface-z -5 --bottom-z 0", dir);
  EXPECT_EQ(code, 2) << err;
  EXPECT_NE(err.find("bounds"), std::string::npos) << err;
  std::tie(code, err) = RunCli(track + " --presence-false-alarm 0.5", dir);
  EXPECT_EQ(code, 2) << err;
  EXPECT_NE(err.find("presence_false_alarm"), std::string::npos) << err;
  std::tie(code, err) = RunCli(track + " --bounds-max inf,inf,100 --surface-z 50", dir);
  EXPECT_EQ(code, 2) << err;
  EXPECT_NE(err.find("--surface-z"), std::string::npos) << err;
  // Well-formed bounds run.
  std::tie(code, err) = RunCli(track + " --bounds-min -inf,-inf,-60 --bounds-max inf,inf,50", dir);
  EXPECT_EQ(code, 0) << err;
#endif
}

// CLI: the array file's "session" settings (clients/io/session_file.h) travel with --server as
// with a local run: `track --server` with the settings in the file writes the estimates local
// `track` writes with the same settings as flags (timings aside), and a flag given wins there too.
TEST_F(CliStreamTest, CliTrackOverServerTakesTheSessionFile) {
#ifndef LOCALIZER_CLI_BIN
  GTEST_SKIP() << "LOCALIZER_CLI_BIN not defined by the build";
#else
  TempDir dir;
  const io::SimulationFiles files = SimulateToFiles(dir, 3.0);
  std::ifstream in(files.array_path);
  nlohmann::json array = nlohmann::json::parse(in);
  array["session"] = {{"particles", 1024},       {"frame_samples", 2048},   {"hop_samples", 1024},
                      {"accel_noise_mps2", 0.5}, {"tdoa_sigma_s", 2.5e-05}, {"seed", 7}};
  std::ofstream(dir.File("session.json")) << array.dump(2);
  const std::string wav = " --wav " + files.wav_path + " --print-every 0 --out ";
  auto [code, err] = RunCli("track --server " + target_ + " --array " + dir.File("session.json") + wav +
                                dir.File("remote.csv") + " --filter-seed 9",
                            dir);
  ASSERT_EQ(code, 0) << err;
  std::tie(code, err) = RunCli("track --array " + files.array_path + wav + dir.File("local.csv") +
                                   " --particles 1024 --frame 2048 --hop 1024 --accel-noise 0.5 --tdoa-sigma-us 25 "
                                   "--filter-seed 9",
                               dir);
  ASSERT_EQ(code, 0) << err;
  const std::vector<std::string> timing_columns = {"tdoa_ms", "filter_ms"};
  const auto remote = CsvWithout(dir.File("remote.csv"), timing_columns);
  EXPECT_GT(remote.size(), 10u);
  EXPECT_EQ(remote, CsvWithout(dir.File("local.csv"), timing_columns));
#endif
}

// CLI: `simulate --server --out DIR` writes what `simulate --out` writes plus an
// estimates.csv equal to tracking the written files offline (timings aside).
TEST_F(CliStreamTest, CliSimulateOverServerMatchesOfflineTrack) {
#ifndef LOCALIZER_CLI_BIN
  GTEST_SKIP() << "LOCALIZER_CLI_BIN not defined by the build";
#else
  TempDir dir;
  const std::string out = dir.File("live");
  const auto [code, err] = RunCli(
      "simulate --scenario tetra-water --duration 3 --rate max "
      "--print-every 5 --server " +
          target_ + " --out " + out,
      dir);
  ASSERT_EQ(code, 0) << err;
  io::SimulationFiles files{out + "/signals.wav", out + "/array.json", out + "/truth.csv"};
  ASSERT_TRUE(io::RunTrack(TrackJobFor(files, dir.File("offline.csv"))).ok());
  const std::vector<std::string> timing_columns = {"tdoa_ms", "filter_ms"};
  const auto live = CsvWithout(out + "/estimates.csv", timing_columns);
  EXPECT_GT(live.size(), 10u);
  EXPECT_EQ(live, CsvWithout(dir.File("offline.csv"), timing_columns));
#endif
}

// CLI: `experiment tws --server` runs the scans through a detection session; the scores are
// the local run's (the same tracker behind the wire), and the round trips are reported.
TEST_F(CliStreamTest, CliTwsExperimentOverServerScoresLikeTheLocalRun) {
#ifndef LOCALIZER_CLI_BIN
  GTEST_SKIP() << "LOCALIZER_CLI_BIN not defined by the build";
#else
  TempDir dir;
  const auto read_lines = [&] {
    std::ifstream in(dir.File("stdout.txt"));
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
  };
  const std::string args = "experiment tws --targets 8 --scans 25 --seed 3";
  const auto [local_code, local_err] = RunCli(args, dir);
  ASSERT_EQ(local_code, 0) << local_err;
  const std::vector<std::string> local = read_lines();
  const auto [code, err] = RunCli(args + " --server " + target_, dir);
  ASSERT_EQ(code, 0) << err;
  const std::vector<std::string> remote = read_lines();
  // The header and every score line (through confirmed_tracks and plots_per_scan) agree.
  ASSERT_GE(local.size(), 9u);
  ASSERT_GE(remote.size(), 11u);
  for (size_t i = 0; i < 9; ++i) EXPECT_EQ(remote[i], local[i]) << "line " << i;
  EXPECT_EQ(remote[9].rfind("server ", 0), 0u) << remote[9];
  EXPECT_EQ(remote[10].rfind("scan_round_trip_ms   p50 ", 0), 0u) << remote[10];
  EXPECT_NE(local[5].find("identity_switches    0"), std::string::npos) << local[5];
#endif
}

// A stream abandoned after `opened` leaves a resumable session; resuming it with the
// token works, and with a wrong token is PERMISSION_DENIED.
TEST_F(CliStreamTest, ResumeAfterCancel) {
  engine::AudioSessionConfig config;
  auto scenario = engine::MakeScenario("tetra-water");
  ASSERT_TRUE(scenario.ok());
  config.sensors_m = scenario->sensors_m;
  config.sample_rate_hz = 11025.0;
  config.tracker.particle.particles = 256;
  std::string id, token;
  {
    auto stream = OpenTrackSession(channel_, config, "resume", "key-resume");
    ASSERT_TRUE(stream.ok()) << stream.status().ToString();
    id = (*stream)->opened().session_id();
    token = (*stream)->opened().resume_token();
    (*stream)->Cancel();
    v1::TrackResponse ignored;
    while ((*stream)->Read(&ignored)) {
    }
    EXPECT_EQ((*stream)->Finish().error_code(), grpc::StatusCode::CANCELLED);
  }
  auto wrong = TrackStream::Resume(channel_, id, token + "x", std::nullopt, "key-resume");
  ASSERT_FALSE(wrong.ok());
  EXPECT_EQ(wrong.status().code(), StatusCode::kPermissionDenied) << wrong.status().message();
  // The server may take a moment to see the cancelled stream detach.
  StatusOr<std::unique_ptr<TrackStream>> resumed = Internal("not tried");
  for (int attempt = 0; attempt < 50; ++attempt) {
    resumed = TrackStream::Resume(channel_, id, token, std::nullopt, "key-resume");
    if (resumed.ok() || resumed.status().code() != StatusCode::kFailedPrecondition) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(resumed.ok()) << resumed.status().message();
  EXPECT_TRUE((*resumed)->opened().resumed());
  EXPECT_EQ((*resumed)->opened().session_id(), id);
  (*resumed)->WritesDone();
  v1::TrackResponse ignored;
  while ((*resumed)->Read(&ignored)) {
  }
  EXPECT_TRUE((*resumed)->Finish().ok());
}

}  // namespace
}  // namespace localizer::client
