// Concurrent real-time sessions on one backend: N sessions (one thread each, as the
// server's workers would run them), 4 channels at 44.1 kHz, 4096-sample frames with a
// 2048-sample hop, 4096 particles; each thread feeds its session one hop-sized block every
// 2048 / 44100 s (starts staggered by a seeded random offset within one hop, or within
// --stagger-s seconds: a service's sessions open over time) and records the frame latency:
// from the instant the block was due to the end of Process. Every session is opened before
// the clock starts (the opening time is printed apart). Prints p50/p99/max per N over all
// frames, and p99 over the steady frames: those due 1 s or more after the clock started
// (every session starts within the first hop, so all of them take their first fix and
// initialise their filter at once, a burst a running service does not see; the frames
// queued behind it are late too; with --stagger-s S, the frames due S + 1 s or more after it),
// and the p99 of each second of the run (by due time), which tells a start-up backlog that
// drains from a steady cost; the goal is p99 <= 50 ms at >= 2000 sessions on one GPU.
// --offline instead runs one session through the audio as fast as it can: milliseconds
// per second of audio (the seed's case: 18.24 ms on a Jetson TX1 GPU, 56.95 ms on its CPU).
//
//   gpu_sessions_bench --backend gpu --sessions 500,1000,2000,3000 --seconds 4
//   gpu_sessions_bench --backend gpu --offline --seconds 4
// Exits 0 with a message when the backend is gpu and there is no device.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <latch>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "engine/core/flags.h"
#include "engine/pipeline/backend.h"
#include "engine/pipeline/session.h"
#include "engine/sim/simulator.h"
#include "gpu/backend/gpu_backend.h"

namespace localizer::engine {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kFrame = 4096, kHop = 2048;

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * static_cast<double>(v.size() - 1))];
}

struct Audio {
  Scenario scenario;
  SimResult sim;
};

Audio MakeAudio(double seconds) {
  Audio a{*MakeScenario("tetra-air", 1), {}};
  a.scenario.sim.sample_rate_hz = 44100.0;
  a.scenario.sim.duration_s = seconds;
  a.sim = *Simulate(*ArrayGeometry::Create(a.scenario.sensors_m, a.scenario.sound_speed_mps), a.scenario.sim);
  return a;
}

AudioSessionConfig ConfigFor(const Audio& a, BackendChoice backend, int particles, uint64_t seed) {
  AudioSessionConfig c;
  c.sensors_m = a.scenario.sensors_m;
  c.sound_speed_mps = a.scenario.sound_speed_mps;
  c.sample_rate_hz = a.sim.sample_rate_hz;
  c.band_low_hz = a.scenario.sim.band_low_hz;
  c.band_high_hz = a.scenario.sim.band_high_hz;
  c.frame_samples = kFrame;
  c.hop_samples = kHop;
  c.tracker.particle.particles = particles;
  // One acceleration std on both backends: the device filter has no acceleration levels (a
  // session with them runs its filter on the CPU), and like is compared with like.
  c.tracker.particle.SetSingleMotion();
  c.backend = backend;
  c.seed = seed;
  return c;
}

// The audio as hop-sized channel-major blocks.
std::vector<std::vector<float>> HopBlocks(const SimResult& sim) {
  std::vector<std::vector<float>> blocks;
  for (int64_t start = 0; start + kHop <= sim.samples_per_channel; start += kHop) {
    std::vector<float> b(static_cast<size_t>(kHop) * sim.channel_count);
    for (int ch = 0; ch < sim.channel_count; ++ch) {
      std::copy_n(sim.samples.data() + ch * sim.samples_per_channel + start, kHop, b.data() + ch * kHop);
    }
    blocks.push_back(std::move(b));
  }
  return blocks;
}

int RunRealtime(const Audio& audio, BackendChoice backend, int sessions, int particles, double stagger_s) {
  const auto blocks = HopBlocks(audio.sim);
  const double hop_s = kHop / audio.sim.sample_rate_hz;
  std::vector<std::vector<double>> latency_ms(sessions);
  std::vector<std::vector<double>> due_s(sessions);  // since the clock started
  const double steady_after_s = 1.0 + stagger_s;
  std::vector<int> failures(sessions, 0);
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> offset(0.0, std::max(hop_s, stagger_s));
  std::vector<double> offsets(sessions);
  for (double& o : offsets) o = offset(rng);
  // Every thread opens its session, then all wait for the clock to start.
  std::latch opened(sessions + 1);
  Clock::time_point t0;
  std::atomic<bool> started{false};
  const auto open_start = Clock::now();
  std::vector<std::thread> threads;
  for (int i = 0; i < sessions; ++i) {
    threads.emplace_back([&, i] {
      auto session = Session::Create(ConfigFor(audio, backend, particles, 1000 + i));
      opened.count_down();
      while (!started.load(std::memory_order_acquire)) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      if (!session.ok()) {
        failures[i] = 1;
        std::fprintf(stderr, "session %d: %s\n", i, session.status().ToString().c_str());
        return;
      }
      std::vector<Estimate> out;
      for (size_t k = 0; k < blocks.size(); ++k) {
        const auto due = t0 + std::chrono::duration_cast<Clock::duration>(
                                  std::chrono::duration<double>(offsets[i] + static_cast<double>(k) * hop_s));
        std::this_thread::sleep_until(due);
        out.clear();
        if (!(*session)->Process({k + 1, 4, kHop, blocks[k].data()}, &out).ok()) ++failures[i];
        // Frames complete from the second block on; the first only fills the ring.
        if (!out.empty()) {
          latency_ms[i].push_back(std::chrono::duration<double, std::milli>(Clock::now() - due).count());
          due_s[i].push_back(offsets[i] + static_cast<double>(k) * hop_s);
        }
      }
    });
  }
  opened.arrive_and_wait();
  const double open_s = std::chrono::duration<double>(Clock::now() - open_start).count();
  t0 = Clock::now() + std::chrono::milliseconds(200);
  started.store(true, std::memory_order_release);
  for (auto& t : threads) t.join();
  std::vector<double> all, steady;
  std::vector<std::vector<double>> by_second;
  int failed = 0;
  for (int i = 0; i < sessions; ++i) {
    all.insert(all.end(), latency_ms[i].begin(), latency_ms[i].end());
    for (size_t f = 0; f < latency_ms[i].size(); ++f) {
      if (due_s[i][f] >= steady_after_s) steady.push_back(latency_ms[i][f]);
      const auto second = static_cast<size_t>(due_s[i][f]);
      if (by_second.size() <= second) by_second.resize(second + 1);
      by_second[second].push_back(latency_ms[i][f]);
    }
    failed += failures[i];
  }
  const gpu::GpuBatchCounts c = gpu::BatchCounts();
  std::printf("%-8s %8d %10zu %9.2f %9.2f %9.2f %10.2f %8d %7.2f %10.1f %10.1f\n", BackendChoiceName(backend), sessions,
              all.size(), Percentile(all, 0.5), Percentile(all, 0.99), Percentile(all, 1.0), Percentile(steady, 0.99),
              failed, open_s,
              c.gcc_batches ? static_cast<double>(c.gcc_frames) / static_cast<double>(c.gcc_batches) : 0.0,
              c.filter_batches ? static_cast<double>(c.filter_steps) / static_cast<double>(c.filter_batches) : 0.0);
  std::printf("  p99 ms by second:");
  for (size_t s = 0; s < by_second.size(); ++s) std::printf(" %zu:%.1f", s, Percentile(by_second[s], 0.99));
  std::printf("\n");
  std::fflush(stdout);
  return failed == 0 ? 0 : 1;
}

int RunOffline(const Audio& audio, BackendChoice backend, int particles) {
  const auto blocks = HopBlocks(audio.sim);
  std::vector<double> ms_per_audio_s;
  for (int rep = 0; rep < 5; ++rep) {
    auto session = Session::Create(ConfigFor(audio, backend, particles, 7));
    if (!session.ok()) {
      std::fprintf(stderr, "%s\n", session.status().ToString().c_str());
      return 1;
    }
    std::vector<Estimate> out;
    const auto start = Clock::now();
    for (size_t k = 0; k < blocks.size(); ++k) (void)(*session)->Process({k + 1, 4, kHop, blocks[k].data()}, &out);
    const double wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    ms_per_audio_s.push_back(wall_ms / (static_cast<double>(blocks.size() * kHop) / audio.sim.sample_rate_hz));
  }
  std::printf("offline %s: %.2f ms per second of audio (median of 5; one session, %d particles)\n",
              BackendChoiceName(backend), Percentile(ms_per_audio_s, 0.5), particles);
  return 0;
}

int Main(int argc, char** argv) {
  std::string backend_name = "gpu", sessions_list = "1,100,500,1000,2000";
  double seconds = 4.0, window_ms = 1.0, stagger_s = 0.0;
  int particles = 4096;
  bool offline = false;
  FlagSet flags("gpu_sessions_bench [flags]", "Concurrent real-time sessions' frame latency on one backend.");
  flags.String("backend", &backend_name, "cpu|gpu", "backend for every session");
  flags.String("sessions", &sessions_list, "N,N,...", "session counts to run, one after another");
  flags.Double("seconds", &seconds, "S", "s", "audio per session");
  flags.Int("particles", &particles, "N", "particles", "per session");
  flags.Double("window-ms", &window_ms, "MS", "ms", "GPU batching window");
  flags.Double("stagger-s", &stagger_s, "S", "s",
               "sessions start at random within S seconds (default: within one hop)");
  flags.Bool("offline", &offline, "one session as fast as possible: ms per audio second");
  const Status parsed = flags.Parse(std::vector<std::string>(argv + 1, argv + argc));
  if (flags.help_requested()) {
    std::printf("%s", flags.Usage().c_str());
    return 0;
  }
  if (!parsed.ok()) {
    std::fprintf(stderr, "%s\n", parsed.message().c_str());
    return 2;
  }
  const auto backend = ParseBackendChoice(backend_name, "--backend");
  if (!backend.ok()) {
    std::fprintf(stderr, "%s\n", backend.status().message().c_str());
    return 2;
  }
  gpu::GpuBackendOptions gpu_options;
  gpu_options.batch_window_s = window_ms * 1e-3;
  if (const Status s = gpu::RegisterGpuBackend(gpu_options); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 2;
  }
  if (*backend == BackendChoice::kGpu && !GpuUnavailableReason().empty()) {
    std::printf("skipped: no usable GPU (%s)\n", GpuUnavailableReason().c_str());
    return 0;
  }
  if (*backend == BackendChoice::kGpu) std::printf("device: %s\n", gpu::DeviceName().c_str());
  const Audio audio = MakeAudio(seconds);
  int code = 0;
  if (offline) {
    code = RunOffline(audio, *backend, particles);
  } else {
    std::printf("%-8s %8s %10s %9s %9s %9s %10s %8s %7s %10s %10s\n", "backend", "sessions", "frames", "p50_ms",
                "p99_ms", "max_ms", "steady_p99", "failed", "open_s", "gcc_batch", "pf_batch");
    std::stringstream list(sessions_list);
    for (std::string item; std::getline(list, item, ',');)
      code |= RunRealtime(audio, *backend, std::stoi(item), particles, stagger_s);
  }
  SetGpuProvider(nullptr);
  return code;
}

}  // namespace
}  // namespace localizer::engine

int main(int argc, char** argv) { return localizer::engine::Main(argc, argv); }
