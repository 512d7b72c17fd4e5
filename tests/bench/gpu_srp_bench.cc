// Throughput of the batched GPU SRP-PHAT (gpu/srp/srp_batch.h): direction-session frames per
// second (one session's frame evaluated over its whole grid, arg-max and refinement included)
// for the case, 4 microphones (the ReSpeaker board), frames of 256 samples every 128 at
// 16 kHz (125 frames per second per session), 100-7000 Hz, batches of 1000 to 8000 sessions,
// on two grids: the CPU's own (CpuLikeGrid: 291 directions on the hemisphere) and a 2562-point
// sphere (an icosphere-like density, as ODAS uses).
//
// Per case, the median over --runs Runs (after 3 warm-ups) of:
//   wall      SrpBatch::Run on the host: staging copy, both transfers, kernels, one sync
//   device    the Run's device time between its first and last copy (events)
//   kernels   the map and peak kernels alone (events)
// and from them frames/s = sessions / time, real-time sessions = frames/s / 125, and the map's
// direction-evaluations/s (sessions x D / kernel time). The sessions' spectra are 64 seeded
// plane waves analysed by the CPU, cycled over the batch; before timing, the first 64 results
// are checked against the CPU's Analyse (largest angle printed).
//
//   gpu_srp_bench [--runs 20] [--sessions 1000,2000,4000,8000]
// Plain main; prints the reason and exits 0 where no device is usable.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "engine/core/flags.h"
#include "gpu/core/device.h"
#include "gpu/srp/srp_batch.h"
#include "gpu/srp/srp_grid.h"
#include "tests/gpu/srp_test_scenes.h"

namespace localizer::gpu {
namespace {

constexpr int kDistinctSessions = 64;
constexpr double kFramesPerSecond = 16000.0 / 128.0;  // one frame per hop

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Frames {
  std::vector<std::vector<std::complex<float>>> spectra;
  std::vector<engine::DirectionPeak> cpu_peaks;
};

Frames MakeFrames(const SrpArrayConfig& config) {
  Frames f;
  StatusOr<SrpArrayModel> model = MakeSrpArrayModel(config.sensors_m, config.options);
  std::mt19937_64 rng(2026);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> up(0.1, 1.0);
  for (int s = 0; s < kDistinctSessions; ++s) {
    StatusOr<engine::SrpPhat> cpu = engine::SrpPhat::Create(config.sensors_m, config.options);
    if (!cpu.ok() || !model.ok()) std::abort();
    // Sources above the board (the CPU reports the normal's side of a planar array).
    const engine::Vec3 u = engine::Vec3(n(rng), n(rng), up(rng)).normalized();
    const std::vector<float> frame = testing::PlaneWave(config.sensors_m, config.options, u, 1.0, 7000 + s);
    StatusOr<std::vector<engine::DirectionPeak>> peaks = cpu->Analyse(frame.data());
    f.cpu_peaks.push_back(peaks.ok() && !peaks->empty() ? (*peaks)[0] : engine::DirectionPeak{});
    f.spectra.push_back(testing::AsFloat(testing::RecoveredSpectra(*cpu, *model)));
  }
  return f;
}

bool RunCase(const char* grid_name, const SrpArrayConfig& config, const Frames& frames, int sessions, int runs) {
  auto batch = SrpBatch::Create({config}, sessions, /*collect_timing=*/true);
  if (!batch.ok()) {
    std::printf("create: %s\n", batch.status().ToString().c_str());
    return false;
  }
  std::vector<SrpPeak> peaks(static_cast<size_t>(sessions));
  std::vector<SrpJob> jobs;
  for (int s = 0; s < sessions; ++s)
    jobs.push_back({0, frames.spectra[static_cast<size_t>(s % kDistinctSessions)].data(), &peaks[static_cast<size_t>(s)]});
  std::vector<double> wall, device, kernels;
  for (int k = 0; k < runs + 3; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    const Status status = (*batch)->Run(jobs);
    const auto t1 = std::chrono::steady_clock::now();
    if (!status.ok()) {
      std::printf("run: %s\n", status.ToString().c_str());
      return false;
    }
    if (k < 3) continue;
    wall.push_back(std::chrono::duration<double>(t1 - t0).count());
    device.push_back(1e-3 * (*batch)->last_timing().total_ms);
    kernels.push_back(1e-3 * (*batch)->last_timing().kernels_ms);
  }
  // Agreement with the CPU on the distinct frames (the CPU-like grid is where it is stated).
  double worst_rad = 0.0;
  for (int s = 0; s < std::min(sessions, kDistinctSessions); ++s) {
    const engine::DirectionPeak& want = frames.cpu_peaks[static_cast<size_t>(s)];
    if (!std::isnan(want.direction.x()))
      worst_rad = std::max(worst_rad, testing::AngleRad(peaks[static_cast<size_t>(s)].direction, want.direction));
  }
  const double d = static_cast<double>((*batch)->directions(0).size());
  const double w = Median(wall), v = Median(device), k = Median(kernels);
  std::printf("%-14s %6d %6.0f %10.3f %10.3f %10.3f %12.3e %12.3e %12.3e %10.0f %12.3e %10.2g\n", grid_name, sessions, d,
              w * 1e3, v * 1e3, k * 1e3, sessions / w, sessions / v, sessions / k, sessions / w / kFramesPerSecond,
              sessions * d / k, worst_rad);
  return true;
}

std::vector<int> ParseSessions(const std::string& text) {
  std::vector<int> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const auto n = ParseInteger(item);
    if (!n.ok() || *n < 1 || *n > (1 << 20)) return {};
    out.push_back(static_cast<int>(*n));
  }
  return out;
}

int Main(int argc, char** argv) {
  int runs = 20;
  std::string sessions_text = "1000,2000,4000,8000";
  FlagSet flags("gpu_srp_bench [--runs N] [--sessions LIST]",
                "Direction-session frames per second of the batched GPU SRP-PHAT (4 mics, 256/128 at 16 kHz).");
  flags.Int("runs", &runs, "N", "", "timed Runs per case (after 3 warm-ups)");
  flags.String("sessions", &sessions_text, "LIST", "batch sizes, comma-separated");
  std::vector<std::string> args(argv + 1, argv + argc);
  if (const Status parsed = flags.Parse(args); !parsed.ok()) {
    std::fprintf(stderr, "gpu_srp_bench: %s\n", parsed.message().c_str());
    return 2;
  }
  if (flags.help_requested()) {
    std::printf("%s", flags.Usage().c_str());
    return 0;
  }
  const std::vector<int> sessions = ParseSessions(sessions_text);
  if (sessions.empty() || runs < 1) {
    std::fprintf(stderr, "gpu_srp_bench: --sessions must list integers in [1, 2^20], --runs be >= 1\n");
    return 2;
  }
  const std::string& reason = DeviceUnavailableReason();
  if (!reason.empty()) {
    std::printf("gpu_srp_bench: skipped, no usable GPU: %s\n", reason.c_str());
    return 0;
  }
  SrpArrayConfig config;
  config.sensors_m = testing::Respeaker4();
  config.options = testing::FrameOptions(256);
  StatusOr<SrpArrayModel> model = MakeSrpArrayModel(config.sensors_m, config.options);
  if (!model.ok()) return 1;
  const Frames frames = MakeFrames(config);
  std::printf("device: %s; 4 mics (ReSpeaker), 256/128 at 16 kHz, 100-7000 Hz: P = %d, B = %d; median of %d runs\n",
              Device().name.c_str(), model->pairs, model->band.bins, runs);
  std::printf("%-14s %6s %6s %10s %10s %10s %12s %12s %12s %10s %12s %10s\n", "grid", "sess", "D", "wall ms", "device ms",
              "kernel ms", "frames/s", "dev frames/s", "krn frames/s", "rt sess", "dir-eval/s", "vs CPU rad");
  SrpArrayConfig cpu_grid = config, sphere = config;
  cpu_grid.directions = CpuLikeGrid(*model);
  sphere.directions = FibonacciDirections(2562);
  for (int n : sessions)
    if (!RunCase("cpu-like", cpu_grid, frames, n, runs)) return 1;
  for (int n : sessions)
    if (!RunCase("sphere-2562", sphere, frames, n, runs)) return 1;
  return 0;
}

}  // namespace
}  // namespace localizer::gpu

int main(int argc, char** argv) { return localizer::gpu::Main(argc, argv); }
