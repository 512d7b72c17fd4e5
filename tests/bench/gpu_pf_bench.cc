// Throughput of the GPU particle bank (gpu/filters/particle_bank.h): particle-steps per
// second for one session of 1e6 particles and for 1000 sessions of 4096 particles stepped
// together, each a full Step (descriptors in, five kernels, results out, one sync), and
// how close that comes to the device's memory bandwidth:
//   fraction of the HBM bound = particle-steps/s x 96 bytes / (measured D2D copy bandwidth)
// 96 bytes is what a step without resampling must move per particle (state read twice and
// written once, 24 bytes each; log-weight read twice and written twice; prior weight read
// and new weight written; 4 bytes each). The copy bandwidth is a large cudaMemcpy
// device-to-device in the same run, counting read + write bytes.
//
// Two likelihood regimes per case: "flat" (a TDOA sigma of 1 s: the ESS stays at N, no
// resampling: the 96-byte path) and "resample" (resample_threshold = 1: every step
// resamples and moves, the worst case).
//
//   gpu_pf_bench [--steps 50]
// Plain main; prints the reason and exits 0 where no device is usable.
#include <cuda_runtime_api.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "engine/core/flags.h"
#include "gpu/core/device.h"
#include "gpu/filters/particle_bank.h"
#include "tests/gpu/pf_test_scenarios.h"

namespace localizer::gpu {
namespace {

constexpr double kBytesPerParticleStep = 96.0;

// Read + write bandwidth of a 1 GiB device-to-device copy, bytes/s (median of 10).
double CopyBandwidth() {
  const std::size_t bytes = std::size_t{1} << 30;
  void *a = nullptr, *b = nullptr;
  if (cudaMalloc(&a, bytes) != cudaSuccess || cudaMalloc(&b, bytes) != cudaSuccess) {
    cudaFree(a);
    cudaGetLastError();
    return 0.0;
  }
  cudaMemset(a, 1, bytes);
  cudaEvent_t start, stop;
  cudaEventCreate(&start);
  cudaEventCreate(&stop);
  std::vector<double> rates;
  for (int k = 0; k < 12; ++k) {
    cudaEventRecord(start);
    cudaMemcpy(b, a, bytes, cudaMemcpyDeviceToDevice);
    cudaEventRecord(stop);
    cudaEventSynchronize(stop);
    float ms = 0.0f;
    cudaEventElapsedTime(&ms, start, stop);
    if (k >= 2) rates.push_back(2.0 * static_cast<double>(bytes) / (ms * 1e-3));
  }
  cudaEventDestroy(start);
  cudaEventDestroy(stop);
  cudaFree(a);
  cudaFree(b);
  std::sort(rates.begin(), rates.end());
  return rates[rates.size() / 2];
}

struct Result {
  double seconds_per_step = 0.0;  // median
  double particle_steps_per_s = 0.0;
  int resampled_sessions = 0;  // in the last step
};

// Opens `sessions` sessions of `particles`, steps them all together `steps` times (after 3
// warm-up steps); the median wall time of a Step.
bool Run(int sessions, int particles, bool resample, int steps, Result* out) {
  auto bank = ParticleBank::Create(0);
  if (!bank.ok()) {
    std::printf("bank: %s\n", bank.status().ToString().c_str());
    return false;
  }
  const testing::CvScenario s;
  engine::ParticleFilterOptions o = testing::CvOptions(particles, 1);
  if (resample) o.resample_threshold = 1.0;
  std::vector<int> slots;
  for (int k = 0; k < sessions; ++k) {
    o.seed = static_cast<uint64_t>(k) + 1;
    auto slot = (*bank)->Open(s.array, o);
    if (!slot.ok()) {
      std::printf("open: %s\n", slot.status().ToString().c_str());
      return false;
    }
    const engine::TrackState belief = s.Belief();
    if (!(*bank)->InitialiseGaussian(*slot, belief.mean, testing::CovarianceRoot(belief.covariance)).ok()) return false;
    slots.push_back(*slot);
  }
  std::mt19937_64 rng(1);
  const engine::Measurement m = testing::MakeMeasurement(s.array, s.p0, s.v, 0.0, s.sigma_s, s.fs, rng);
  const std::vector<int> used(m.pairs.size(), 1);
  const std::vector<double> sigmas(m.pairs.size(), resample ? 8e-6 : 1.0);
  std::vector<ParticleBank::StepRequest> requests;
  for (int slot : slots) requests.push_back({slot, 0.01, &m, used.data(), sigmas.data()});
  std::vector<ParticleBank::StepResult> results(requests.size());
  std::vector<double> times;
  for (int k = 0; k < steps + 3; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    const Status status = (*bank)->Step(requests, results);
    const auto t1 = std::chrono::steady_clock::now();
    if (!status.ok()) {
      std::printf("step: %s\n", status.ToString().c_str());
      return false;
    }
    if (k >= 3) times.push_back(std::chrono::duration<double>(t1 - t0).count());
  }
  std::sort(times.begin(), times.end());
  out->seconds_per_step = times[times.size() / 2];
  out->particle_steps_per_s = static_cast<double>(sessions) * particles / out->seconds_per_step;
  out->resampled_sessions = 0;
  for (const auto& r : results) out->resampled_sessions += r.resampled;
  return true;
}

int Main(int argc, char** argv) {
  int steps = 50;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--steps") == 0) {
      const auto n = localizer::ParseInteger(argv[i + 1]);
      if (!n.ok() || *n > 1000000) {
        std::fprintf(stderr, "gpu_pf_bench: --steps must be an integer <= 1000000, got \"%s\"\n", argv[i + 1]);
        return 2;
      }
      steps = static_cast<int>(std::max<int64_t>(1, *n));  // 0 and below: 1, as before
    }
  }
  const std::string& reason = DeviceUnavailableReason();
  if (!reason.empty()) {
    std::printf("gpu_pf_bench: skipped, no usable GPU: %s\n", reason.c_str());
    return 0;
  }
  const double copy = CopyBandwidth();
  std::printf("device: %s; D2D copy bandwidth (read + write): %.0f GB/s\n", Device().name.c_str(), copy / 1e9);
  std::printf("%-26s %-9s %12s %18s %12s %10s\n", "case", "regime", "step (us)", "particle-steps/s", "HBM frac",
              "resampled");
  struct Case {
    const char* name;
    int sessions, particles;
  };
  for (const Case c : {Case{"1 session x 1e6", 1, 1000000}, Case{"1000 sessions x 4096", 1000, 4096}}) {
    for (bool resample : {false, true}) {
      Result r;
      if (!Run(c.sessions, c.particles, resample, steps, &r)) return 1;
      const double fraction = copy > 0.0 ? r.particle_steps_per_s * kBytesPerParticleStep / copy : 0.0;
      std::printf("%-26s %-9s %12.1f %18.3e %12.3f %10d\n", c.name, resample ? "resample" : "flat",
                  r.seconds_per_step * 1e6, r.particle_steps_per_s, fraction, r.resampled_sessions);
    }
  }
  return 0;
}

}  // namespace
}  // namespace localizer::gpu

int main(int argc, char** argv) { return localizer::gpu::Main(argc, argv); }
