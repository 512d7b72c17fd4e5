// localizer-cli experiment tws: track-while-scan on a simulated rotating radar (the seed's
// 33 rpm, 1800 Hz PRF): N targets in Poisson clutter with P_D < 1, scored against the
// simulator's truth with OSPA, GOSPA and identity switches, and timed. With --server the
// scans go through a detection session on a localizer-server instead (the same tracker, so
// the same scores), and the scans' round trips are timed.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "clients/cli/commands.h"
#include "clients/cli/experiment_commands.h"
#include "clients/cli/server_flags.h"
#include "engine/sim/radar_scan.h"
#include "engine/tws/ospa.h"
#include "engine/tws/track_scoring.h"
#include "engine/tws/tws_tracker.h"
#ifdef LOCALIZER_CLI_OFFLINE
#include "clients/cli/full_cli.h"
#else
#include "clients/grpc/connection.h"
#include "clients/grpc/remote_scan_session.h"
#endif

namespace localizer::cli {
namespace {

const char* const kCommand = "experiment tws";

struct TwsFlags {
  int targets = 8;
  double clutter_per_m2 = 1e-9;
  int scans = 50;
  uint64_t seed = 1;
  double pd = 0.9;
  double range_sigma_m = 10.0;
  double bearing_sigma_rad = 0.01;
  double max_range_m = 0.0;
  double min_separation_m = 1000.0;
  double accel_noise_mps2 = 5.0;
  std::string filter = "kalman";
  std::string initiation = "one-point";
  double ospa_cutoff_m = 1000.0;
  double ospa_order = 2.0;
  std::string server;              // HOST:PORT: run the scans through a detection session there
  client::ConnectOptions connect;  // credentials for --server
  std::string session_key;         // "" with --server: a random one
};

Status Check(const TwsFlags& f) {
  if (f.targets < 0 || f.targets > 100000) return InvalidArgument("--targets must be in 0..100000");
  if (f.scans < 1 || f.scans > 100000) return InvalidArgument("--scans must be in 1..100000");
  if (!(f.pd >= 0.0 && f.pd <= 1.0)) return InvalidArgument("--pd must be in [0, 1]");
  if (!(f.clutter_per_m2 >= 0.0) || !std::isfinite(f.clutter_per_m2))
    return InvalidArgument("--clutter must be a finite density >= 0 (false plots per m^2 per scan)");
  if (f.filter != "kalman" && f.filter != "steady-state")
    return InvalidArgument("--filter is \"" + f.filter + "\", must be kalman or steady-state");
  if (f.initiation != "one-point" && f.initiation != "two-point")
    return InvalidArgument("--initiation is \"" + f.initiation + "\", must be one-point or two-point");
  if (!(f.ospa_cutoff_m > 0.0)) return InvalidArgument("--ospa-cutoff-m must be > 0");
  if (!(f.ospa_order >= 1.0)) return InvalidArgument("--ospa-order must be >= 1");
  if (!(f.min_separation_m >= 0.0)) return InvalidArgument("--min-separation-m must be >= 0");
  return Status::Ok();
}

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t i = static_cast<size_t>(std::ceil(p * static_cast<double>(v.size()))) - 1;
  return v[std::min(i, v.size() - 1)];
}

}  // namespace

int RunTwsExperiment(const std::vector<std::string>& args) {
  TwsFlags f;
  FlagSet flags("localizer-cli experiment tws [flags]",
                "Track-while-scan on a simulated rotating radar (33 rpm: one scan per 1.8182 s;\n"
                "PRF 1800 Hz: 83.3 km unambiguous range). Targets are placed at random in the\n"
                "annulus 5 km .. 0.8 x max range (every fifth in a coordinated turn), detected with\n"
                "probability --pd, among Poisson clutter uniform over the annulus. Prints OSPA (mean,\n"
                "95th percentile over scans after the first 5), GOSPA mean, identity switches,\n"
                "confirmed tracks and track updates per second (the tracker's wall time only).");
  flags.Int("targets", &f.targets, "N", "", "number of targets");
  flags.Double("clutter", &f.clutter_per_m2, "DENSITY", "per m^2 per scan",
               "clutter density (1e-9 over the default 83 km annulus: ~22 false plots per scan)");
  flags.Int("scans", &f.scans, "K", "", "radar revolutions");
  flags.Uint64("seed", &f.seed, "S", "seed of the targets' placement and of every scan's draws");
  flags.Double("pd", &f.pd, "P", "", "detection probability of a target per scan");
  flags.Double("range-sigma-m", &f.range_sigma_m, "M", "m", "range noise std (sensor and tracker)");
  flags.Double("bearing-sigma-rad", &f.bearing_sigma_rad, "R", "rad", "bearing noise std (sensor and tracker)");
  flags.Double("max-range-m", &f.max_range_m, "M", "m", "outer edge of the surveillance annulus; 0: c / (2 PRF)");
  flags.Double("min-separation-m", &f.min_separation_m, "M", "m", "least distance between targets at the start");
  flags.Double("accel-noise-mps2", &f.accel_noise_mps2, "A", "m/s^2", "tracker's constant-velocity process noise std");
  flags.String("filter", &f.filter, "kalman|steady-state",
               "per-track filter (steady-state freezes the converged gain)");
  flags.String("initiation", &f.initiation, "one-point|two-point", "how unassociated plots start tentative tracks");
  flags.Double("ospa-cutoff-m", &f.ospa_cutoff_m, "C", "m", "OSPA / GOSPA cut-off c");
  flags.Double("ospa-order", &f.ospa_order, "P", "", "OSPA / GOSPA order p (GOSPA alpha = 2)");
  RegisterServerFlag(flags, &f.server, /*required=*/false, &f.connect);
  flags.String("session-key", &f.session_key, "KEY", "with --server: x-localizer-session-key (default: random)");
  if (auto exit_code = ParseFlagsOrExit(kCommand, flags, args)) return *exit_code;
  if (const Status st = Check(f); !st.ok()) return UsageError(kCommand, st.message());

  engine::RadarScanOptions radar;
  radar.range_sigma_m = f.range_sigma_m;
  radar.bearing_sigma_rad = f.bearing_sigma_rad;
  radar.detection_probability = f.pd;
  radar.clutter_density_per_m2 = f.clutter_per_m2;
  radar.max_range_m = f.max_range_m;
  radar.seed = f.seed;
  if (const Status st = radar.Validate(); !st.ok()) return UsageError(kCommand, st.message());
  auto targets = engine::RandomTargets(f.targets, 5000.0, 0.8 * radar.OuterRangeM(), f.min_separation_m, f.seed);
  if (static_cast<int>(targets.size()) < f.targets)
    return UsageError(kCommand, "cannot place " + std::to_string(f.targets) + " targets " +
                                    std::to_string(f.min_separation_m) + " m apart; lower --min-separation-m");
  auto sim = engine::RadarScanSimulator::Create(radar, std::move(targets));
  if (!sim.ok()) return UsageError(kCommand, sim.status().message());

  engine::tws::TwsOptions options;
  options.noise.range_sigma_m = f.range_sigma_m;
  options.noise.bearing_sigma_rad = f.bearing_sigma_rad;
  options.accel_noise_mps2 = f.accel_noise_mps2;
  options.filter = f.filter == "kalman" ? engine::tws::FilterForm::kKalman : engine::tws::FilterForm::kSteadyState;
  options.initiation =
      f.initiation == "one-point" ? engine::tws::Initiation::kOnePoint : engine::tws::Initiation::kTwoPoint;
  // One scan through the tracker: the confirmed (and coasting) tracks after it.
  std::unique_ptr<engine::tws::TwsTracker> tracker;
  if (f.server.empty()) {
    auto made = engine::tws::TwsTracker::Create(options);
    if (!made.ok()) return UsageError(kCommand, made.status().message());
    tracker = std::move(made).value();
  }
#ifdef LOCALIZER_CLI_OFFLINE
  // The rest of this function runs the scans locally; through a server, localizer-cli-full
  // runs them (main sent the command there already: NeedsFullCli).
  if (!tracker) return ExecFullCli("experiment tws --server");
#else
  std::unique_ptr<client::RemoteScanSession> remote;
  std::vector<double> round_trip_s, server_total_s;
  if (!tracker) {
    engine::DetectionSessionConfig config;
    config.tws = options;
    auto channel = client::Connect(f.server, f.connect);
    if (!channel.ok()) return RuntimeError(kCommand, channel.status());
    auto made = client::RemoteScanSession::Open(*channel, config, "experiment-tws",
                                                f.session_key.empty() ? client::RandomSessionKey() : f.session_key);
    if (!made.ok()) return RuntimeError(kCommand, made.status());
    remote = std::move(made).value();
  }
  engine::ScanResult remote_result;
#endif
  const auto process = [&](const engine::Scan& scan, engine::tws::ScanSummary* summary,
                           std::vector<engine::tws::TrackReport>* confirmed) -> Status {
    if (tracker) {
      LOCALIZER_RETURN_IF_ERROR(tracker->Process(scan, summary));
      tracker->Tracks(confirmed, /*include_tentative=*/false);
      return Status::Ok();
    }
#ifdef LOCALIZER_CLI_OFFLINE
    return Internal("no tracker");  // unreachable: the scans ran locally or in localizer-cli-full
#else
    LOCALIZER_RETURN_IF_ERROR(remote->Process(scan, &remote_result));
    round_trip_s.push_back(remote->last_round_trip_s());
    server_total_s.push_back(remote->last_server_total_s());
    *summary = remote_result.summary;
    confirmed->clear();
    for (const auto& t : remote_result.tracks) {
      if (t.status != engine::tws::TrackStatus::kTentative) confirmed->push_back(t);
    }
    return Status::Ok();
#endif
  };

  engine::tws::TrackScoring scoring(f.ospa_cutoff_m);
  std::vector<double> ospa, gospa;
  std::vector<engine::tws::TrackReport> tracks;
  double tracker_s = 0.0;
  int64_t updates = 0, plots = 0;
  double confirmed_sum = 0.0;
  const int skip = options.confirm_window;  // start-up scans left out of the averages
  for (int k = 0; k < f.scans; ++k) {
    const engine::RadarScanFrame frame = sim->Frame(k);
    engine::tws::ScanSummary summary;
    const auto start = std::chrono::steady_clock::now();
    const Status st = process(frame.scan, &summary, &tracks);
    tracker_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!st.ok()) return RuntimeError(kCommand, st);
    updates += summary.track_updates;
    plots += summary.plots;
    std::vector<Eigen::Vector3d> truth_p, track_p;
    std::vector<engine::tws::Labelled> truth_l, track_l;
    for (const auto& t : frame.truth) {
      truth_p.push_back(t.position_m);
      truth_l.push_back({t.id, t.position_m});
    }
    for (const auto& t : tracks) {
      track_p.push_back(t.position_m);
      track_l.push_back({t.id, t.position_m});
    }
    scoring.Add(truth_l, track_l);
    if (k < skip && f.scans > skip) continue;
    ospa.push_back(engine::tws::Ospa(truth_p, track_p, f.ospa_cutoff_m, f.ospa_order));
    gospa.push_back(engine::tws::Gospa(truth_p, track_p, f.ospa_cutoff_m, f.ospa_order).gospa);
    confirmed_sum += static_cast<double>(tracks.size());
  }
  double ospa_mean = 0.0, gospa_mean = 0.0;
  for (double v : ospa) ospa_mean += v / static_cast<double>(ospa.size());
  for (double v : gospa) gospa_mean += v / static_cast<double>(gospa.size());
  std::printf(
      "# tws: %d targets, clutter %g /m^2 (%.1f false plots per scan), P_D %g, %d scans of %.4f s,"
      " seed %llu\n",
      f.targets, f.clutter_per_m2, f.clutter_per_m2 * radar.AreaM2(), f.pd, f.scans, radar.period_s(),
      static_cast<unsigned long long>(f.seed));
  std::printf("# filter %s, initiation %s; OSPA/GOSPA c = %g m, p = %g, over scans %d..%d\n", f.filter.c_str(),
              f.initiation.c_str(), f.ospa_cutoff_m, f.ospa_order, f.scans > skip ? skip : 0, f.scans - 1);
  std::printf("ospa_mean_m          %.1f\n", ospa_mean);
  std::printf("ospa_p95_m           %.1f\n", Percentile(ospa, 0.95));
  std::printf("gospa_mean_m         %.1f\n", gospa_mean);
  std::printf("identity_switches    %d\n", scoring.identity_switches());
  std::printf("track_purity         %.4f\n", scoring.Purity());
  std::printf("confirmed_tracks     %zu (mean %.1f)\n", tracks.size(),
              confirmed_sum / static_cast<double>(ospa.size()));
  std::printf("plots_per_scan       %.1f\n", static_cast<double>(plots) / f.scans);
#ifndef LOCALIZER_CLI_OFFLINE
  if (remote) {
    // Through the server: the scans' round trips (tentative tracks included in the count).
    std::printf("server               %s (session %s)\n", f.server.c_str(), remote->opened().session_id().c_str());
    std::printf("scan_round_trip_ms   p50 %.3f  p95 %.3f  p99 %.3f  max %.3f\n", 1e3 * Percentile(round_trip_s, 0.5),
                1e3 * Percentile(round_trip_s, 0.95), 1e3 * Percentile(round_trip_s, 0.99),
                1e3 * Percentile(round_trip_s, 1.0));
    std::printf("server_total_ms      p50 %.3f  p99 %.3f\n", 1e3 * Percentile(server_total_s, 0.5),
                1e3 * Percentile(server_total_s, 0.99));
    if (const Status closed = remote->Close(); !closed.ok()) return RuntimeError(kCommand, closed);
    return kExitOk;
  }
#endif
  std::printf("track_updates        %lld\n", static_cast<long long>(updates));
  std::printf("tracker_wall_s       %.4f\n", tracker_s);
  std::printf("track_updates_per_s  %.3g\n", tracker_s > 0.0 ? static_cast<double>(updates) / tracker_s : 0.0);
  return kExitOk;
}

}  // namespace localizer::cli
