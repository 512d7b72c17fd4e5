// localizer-cli simulate: a named scenario to signals.wav, array.json and truth.csv, or,
// with --server, streamed live through a localizer-server session and scored.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "clients/cli/commands.h"
#include "clients/cli/server_flags.h"
#include "clients/cli/session_flags.h"
#include "clients/io/array_json.h"
#include "clients/io/room_scene_files.h"
#include "clients/io/score.h"
#include "clients/io/simulation_files.h"
#include "clients/io/track_runner.h"
#include "engine/sim/random_scene.h"
#include "engine/sim/simulator.h"
#ifdef LOCALIZER_CLI_OFFLINE
#include "clients/cli/full_cli.h"
#else
#include "clients/cli/server_stream.h"
#include "clients/grpc/connection.h"
#include "clients/grpc/remote_track.h"
#include "clients/grpc/streamer.h"
#endif

namespace localizer::cli {

namespace {

const char* const kCommand = "simulate";

struct SimulateFlags {
  std::string scenario_name;
  std::string room_path;     // --room: a room scene file (room_scene_files.h)
  std::string array_path;    // --array: with --room
  uint64_t random_seed = 0;  // --random: a scene drawn from this seed (random_scene.h)
  std::string out_dir;
  uint64_t seed = 1;
  std::optional<double> duration_s;
  bool list = false;
  SessionFlags session;
  StreamFlags stream;
  int print_every = 10;
};

// The flags that only mean something with --server.
std::vector<std::string> ServerOnlyFlags() {
  std::vector<std::string> names = {"frame",         "hop",         "particles", "likelihood",  "filter-seed",
                                    "tdoa-sigma-us", "accel-noise", "backend",   "sound-speed", "reference",
                                    "weighting",     "phat-beta",   "band-low",  "band-high",   "print-every"};
  for (const std::string& name : StreamFlagNames()) names.push_back(name);
  return names;
}

int ListScenarios() {
  for (const std::string& name : engine::ScenarioNames()) {
    auto scenario = engine::MakeScenario(name);
    if (!scenario.ok()) return RuntimeError(kCommand, scenario.status());
    std::string padded = name;
    padded.resize(std::max<size_t>(padded.size() + 2, 18), ' ');
    std::cout << padded << scenario->description << "\n";
  }
  return kExitOk;
}

bool IsScenario(const std::string& name) {
  const std::vector<std::string> names = engine::ScenarioNames();
  return std::find(names.begin(), names.end(), name) != names.end();
}

// A random scene (engine/sim/random_scene.h) simulated as the named scenarios are.
StatusOr<io::SimulationRun> SimulateRandomScene(uint64_t seed, std::optional<double> duration_s) {
  engine::RandomSceneOptions options;
  if (duration_s) options.duration_s = *duration_s;
  auto scene = engine::DrawRandomScene(seed, options);
  if (!scene.ok()) return scene.status();
  auto array = engine::ArrayGeometry::Create(scene->scenario.sensors_m, scene->scenario.sound_speed_mps);
  if (!array.ok()) return array.status();
  auto result = engine::Simulate(*array, scene->scenario.sim);
  if (!result.ok()) return result.status();
  io::SimulationRun run;
  run.scenario = scene->scenario;
  run.result = std::move(*result);
  run.reference_sensor = array->reference_sensor();
  return run;
}

// What only --server needs (localizer-cli-full).
#ifndef LOCALIZER_CLI_OFFLINE
// The array file simulate writes (simulation_files.h), so that the live session is
// configured exactly as `track` would be on the written files.
io::ArrayFile ArrayFileOf(const io::SimulationRun& run) {
  io::ArrayFile array;
  array.sensors_m = run.scenario.sensors_m;
  array.sound_speed_mps = run.scenario.sound_speed_mps;
  array.sample_rate_hz = run.result.sample_rate_hz;
  array.reference_sensor = run.reference_sensor;
  array.band_hz = std::make_pair(run.scenario.sim.band_low_hz, run.scenario.sim.band_high_hz);
  return array;
}

void PrintLiveEstimate(const engine::Estimate& e, const engine::SimResult& truth) {
  if (!e.initialised) {
    std::printf("frame=%llu t_s=%.3f initialised=0\n", static_cast<unsigned long long>(e.frame_index), e.t_s);
  } else {
    const double error_m = (e.state.head<3>() - truth.TruthAt(e.t_s).position_m).norm();
    std::printf("frame=%llu t_s=%.3f x_m=%.3f y_m=%.3f z_m=%.3f err_m=%.3f\n",
                static_cast<unsigned long long>(e.frame_index), e.t_s, e.state[0], e.state[1], e.state[2], error_m);
  }
  std::fflush(stdout);
}

// The `score` command's numbers for what arrived.
void PrintScore(const client::StreamResult& result, const engine::SimResult& truth) {
  std::vector<io::EstimateRow> rows;
  uint64_t initialised = 0;
  for (const client::StreamedEstimate& s : result.estimates) {
    const engine::Estimate& e = s.estimate;
    rows.push_back({e.t_s, e.state.head<3>(), e.state.tail<3>(), e.initialised});
    if (e.initialised) ++initialised;
  }
  std::printf("estimates=%zu initialised=%llu blocks=%llu audio_s=%.3f wall_s=%.3f\n", result.estimates.size(),
              static_cast<unsigned long long>(initialised), static_cast<unsigned long long>(result.blocks_sent),
              static_cast<double>(result.samples_sent_per_channel) / truth.sample_rate_hz, result.wall_s);
  auto score = io::Score(truth.truth, rows);
  if (score.ok()) {
    std::printf("error %s\n", io::FormatScore(*score).c_str());
  } else {
    std::printf("error n=0 (%s)\n", score.status().message().c_str());
  }
}

int RunOnServer(const SimulateFlags& f, const FlagSet& flags, const io::SimulationRun& run) {
  auto options = ParseStreamFlags(f.stream);
  if (!options.ok()) return UsageError(kCommand, options.status().message());
  const engine::SimResult& sim = run.result;
  const io::ArrayFile array_file = ArrayFileOf(run);
  auto config = BuildSessionConfig(f.session, flags, array_file, sim.sample_rate_hz, Runs::kOnServer);
  if (!config.ok()) return UsageError(kCommand, config.status().message());
  auto array = engine::ArrayGeometry::Create(config->sensors_m, config->sound_speed_mps, config->reference_sensor);
  if (!array.ok()) return RuntimeError(kCommand, array.status());

  std::unique_ptr<io::EstimatesWriter> writer;
  if (!f.out_dir.empty()) {
    auto files = io::WriteSimulationFiles(f.out_dir, run);
    if (!files.ok()) return RuntimeError(kCommand, files.status());
    auto opened = io::OpenEstimatesWriter((std::filesystem::path(f.out_dir) / "estimates.csv").string(),
                                          io::EstimatesFormat::kCsv, &*array);
    if (!opened.ok()) return RuntimeError(kCommand, opened.status());
    writer = std::move(*opened);
  }

  auto channel = client::Connect(f.stream.server, f.stream.connect);
  if (!channel.ok()) return RuntimeError(kCommand, channel.status());
  auto stream = client::OpenTrackSession(*channel, *config, options->label, options->session_key);
  if (!stream.ok()) return RuntimeError(kCommand, stream.status());
  PrintOpened((*stream)->opened());

  client::StreamOptions stream_options;
  stream_options.channel_count = sim.channel_count;
  stream_options.sample_rate_hz = sim.sample_rate_hz;
  stream_options.block_samples = options->block_samples;
  stream_options.pacing = options->pacing;
  stream_options.encoding = options->encoding;
  Status csv_status;
  client::StreamCallbacks callbacks;
  const auto every = static_cast<uint64_t>(f.print_every);
  client::TrackStream& track_stream = **stream;
  callbacks.on_estimate = [&](const client::StreamedEstimate& s) {
    if (every > 0 && s.estimate.frame_index % every == 0) PrintLiveEstimate(s.estimate, sim);
    if (writer && csv_status.ok()) {
      csv_status = writer->Write(s.estimate);
      if (!csv_status.ok()) track_stream.Cancel();
    }
  };
  callbacks.on_rejected = [](const client::BlockRejection& r) {
    Warning(kCommand,
            "block " + std::to_string(r.sequence) + " rejected: " + r.code + " (" + r.reason + "): " + r.message);
  };
  const client::StreamResult result = client::StreamBlocks(
      track_stream, client::ChannelMajorSource(sim.samples.data(), sim.channel_count, sim.samples_per_channel),
      stream_options, callbacks);
  if (!csv_status.ok()) return RuntimeError(kCommand, csv_status);
  if (writer) {
    const Status closed = writer->Close();
    if (!closed.ok()) return RuntimeError(kCommand, closed);
  }
  PrintScore(result, sim);
  PrintStreamTotals(result);
  const Status status = result.status();
  if (!status.ok()) return RuntimeError(kCommand, status);
  return kExitOk;
}
#endif

// --room: the scene rendered for the array, written to --out.
int RunRoomScene(const SimulateFlags& f) {
  auto scene = io::ReadRoomSceneJson(f.room_path);
  if (!scene.ok()) return RuntimeError(kCommand, scene.status());
  auto array = io::ReadArrayFile(f.array_path, io::ArrayUse::kAuto);
  if (!array.ok()) return RuntimeError(kCommand, array.status());
  auto files = io::SimulateRoomScene(*scene, *array, f.seed, f.duration_s, f.out_dir);
  if (!files.ok()) {
    return RuntimeError(kCommand, Status(files.status().code(), f.room_path + ": " + files.status().message()));
  }
  const engine::RoomScene& s = scene->scene;
  std::printf(
      "simulated room %gx%gx%g m, RT60 %g s: %zu source(s), %zu channels, %.3f s at %g Hz, seed %llu -> %s "
      "(signals.wav, array.json, sources.csv, sounding.csv)\n",
      s.room.size_m.x(), s.room.size_m.y(), s.room.size_m.z(), s.room.rt60_s, s.sources.size(), array->sensors_m.size(),
      static_cast<double>(files->samples_per_channel) / s.sample_rate_hz, s.sample_rate_hz,
      static_cast<unsigned long long>(f.seed), f.out_dir.c_str());
  return kExitOk;
}

}  // namespace

int RunSimulate(const std::vector<std::string>& args) {
  SimulateFlags f;
  FlagSet flags(
      "localizer-cli simulate --scenario NAME --out DIR [flags] | --list\n"
      "       localizer-cli simulate --random SEED --out DIR [flags]\n"
      "       localizer-cli simulate --room SCENE.json --array ARRAY.json --out DIR [--seed S] [--duration S]\n"
      "       localizer-cli simulate --scenario NAME --server HOST:PORT [--out DIR] [flags]",
      "Simulates a named scenario (engine/sim) and writes DIR/signals.wav (float32,\n"
      "channel k = sensor k), DIR/array.json (with sample_rate_hz) and DIR/truth.csv.\n"
      "With --server the simulated array streams live (--rate realtime by default) through\n"
      "a tracking session on a localizer-server, configured as `track` would be on the\n"
      "written files. Every Nth estimate is printed with its error against the truth;\n"
      "at the end the error statistics (as `score` computes them), the client latency\n"
      "(block sent -> estimate received) p50/p95/p99 and the rejected blocks. --out then\n"
      "also writes DIR/estimates.csv.\n"
      "--random SEED simulates a scene drawn at random from SEED instead (geometry, medium,\n"
      "range, SNR, spectrum, echoes, impulses: engine/sim/random_scene.h; the seeds\n"
      "scene_campaign prints), written and streamed the same way.\n"
      "--room SCENE.json renders your array (--array) in a shoebox room by the image-source\n"
      "method: fixed sources emitting broadband noise, tones or speech-like bursts, with\n"
      "sensor noise (the scene file's format: clients/io/room_scene_files.h; named scenes in\n"
      "scenes/). It writes DIR/signals.wav, DIR/array.json (sensors moved into the room),\n"
      "DIR/sources.csv (each source's position, range and direction from the array) and\n"
      "DIR/sounding.csv (when each source is heard); `track` or `doa` then runs on them.");
  flags.String("scenario", &f.scenario_name, "NAME", "scenario to simulate (see --list)");
  flags.String("out", &f.out_dir, "DIR", "output directory, created if missing");
  flags.String("room", &f.room_path, "FILE", "render a room scene file for --array instead of a scenario");
  flags.String("array", &f.array_path, "FILE", "with --room: the array file (array.json) to render for");
  flags.Uint64("random", &f.random_seed, "SEED", "simulate a random scene drawn from SEED instead of a named scenario");
  flags.Uint64("seed", &f.seed, "S", "random seed of the scenario: source signal, noise, jitter");
  flags.OptionalDouble("duration", &f.duration_s, "S", "the scenario's own", "seconds of recording to simulate");
  flags.Bool("list", &f.list, "print the scenario names and descriptions, then exit");
  RegisterServerFlag(flags, &f.stream.server, /*required=*/false, &f.stream.connect);
  RegisterStreamFlags(flags, &f.stream, "realtime");
  flags.Int("print-every", &f.print_every, "N", "frames",
            "with --server: print every Nth estimate with its error (0: none)");
  RegisterTrackerFlags(flags, &f.session, "filter-seed");
  RegisterGccFlags(flags, &f.session);
  if (auto exit_code = ParseFlagsOrExit(kCommand, flags, args)) return *exit_code;
  if (f.list) return ListScenarios();
  const bool remote = !f.stream.server.empty();
#ifdef LOCALIZER_CLI_OFFLINE
  if (remote) return ExecFullCli("simulate --server");  // main sent it there already (NeedsFullCli)
#endif
  const bool random = flags.seen("random");
  if (!f.room_path.empty()) {
    if (random || !f.scenario_name.empty()) return UsageError(kCommand, "--room excludes --scenario and --random");
    if (remote) return UsageError(kCommand, "--room writes files; stream them with `track --server`");
    if (f.array_path.empty()) return UsageError(kCommand, "--room needs --array");
    if (f.out_dir.empty()) return UsageError(kCommand, "missing required flag --out");
    if (f.duration_s && *f.duration_s <= 0.0) return UsageError(kCommand, "--duration must be > 0");
    for (const std::string& name : ServerOnlyFlags()) {
      if (flags.seen(name)) return UsageError(kCommand, "--" + name + " is not used by --room");
    }
    return RunRoomScene(f);
  }
  if (!f.array_path.empty()) return UsageError(kCommand, "--array is for --room");
  if (random && !f.scenario_name.empty()) return UsageError(kCommand, "--random and --scenario exclude each other");
  if (random && flags.seen("seed"))
    return UsageError(kCommand, "--seed is a named scenario's; --random SEED seeds the whole scene");
  if (!random && f.scenario_name.empty()) return UsageError(kCommand, "missing required flag --scenario");
  if (!remote) {
    if (f.out_dir.empty()) return UsageError(kCommand, "missing required flag --out");
    for (const std::string& name : ServerOnlyFlags()) {
      if (flags.seen(name)) return UsageError(kCommand, "--" + name + " needs --server");
    }
  }
  if (f.duration_s && *f.duration_s <= 0.0) return UsageError(kCommand, "--duration must be > 0");
  if (f.print_every < 0) return UsageError(kCommand, "--print-every must be >= 0");
  if (!random && !IsScenario(f.scenario_name)) {
    return UsageError(kCommand, "unknown scenario \"" + f.scenario_name + "\" (see --list)");
  }

  auto run = random ? SimulateRandomScene(f.random_seed, f.duration_s)
                    : io::SimulateScenario(f.scenario_name, f.seed, f.duration_s);
  if (!run.ok()) return RuntimeError(kCommand, run.status());
#ifndef LOCALIZER_CLI_OFFLINE
  if (remote) return RunOnServer(f, flags, *run);
#endif
  auto files = io::WriteSimulationFiles(f.out_dir, *run);
  if (!files.ok()) return RuntimeError(kCommand, files.status());
  const engine::SimResult& r = run->result;
  std::printf(
      "simulated %s: %d channels, %.3f s at %g Hz, seed %llu -> %s (signals.wav, "
      "array.json, truth.csv)\n",
      run->scenario.name.c_str(), r.channel_count, static_cast<double>(r.samples_per_channel) / r.sample_rate_hz,
      r.sample_rate_hz, static_cast<unsigned long long>(random ? f.random_seed : f.seed), f.out_dir.c_str());
  if (random) std::printf("scene: %s\n", run->scenario.description.c_str());
  return kExitOk;
}

}  // namespace localizer::cli
