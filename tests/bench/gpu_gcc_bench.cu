// The batched GPU GCC-PHAT stage (gpu/tdoa/gcc_batch.h) against the bare batched cuFFT work
// it cannot avoid, measured side by side in one process.
//
// Frames: 4 channels (tetrahedron, 2 m edges, c = 1500 m/s), 44.1 kHz, 4096 samples, PHAT,
// band 200 Hz .. 0.4 fs, sinc refinement, keep_gcc (N = 5120, windows of 2 x 61 + 1 lags).
// For batches of 1, 16, 256 and 1024 frames, alternating in each repetition:
//   run    GccBatch::Run on pageable frames: host wall time (copy into pinned staging, the
//          whole launch sequence, synchronisation, filling the Measurements), and its CUDA
//          event times: device = pack .. peak (the pack kernel reads the frames from pinned
//          host memory over the bus), total = first H2D start .. last D2H end
//   pinned the same on frames already in pinned memory (frame_pinned: as GpuTdoaEstimator
//          stages them on each session's own thread), host wall time
//   ring   the same on pinned frames sent through each job's own device sample ring
//          (GccJob::ring) at a 50 % hop: only the new half of each channel crosses the bus.
//          Each channel of these frames repeats its first half, so the same frame is a
//          valid next frame of its stream every round (the tests check what rings read back)
//   bare   one R2C over frames x 4 rows and one C2R over frames x 3 rows of N on device
//          buffers (cuFFT plans made once), timed by events: the floor for the stage
// and prints medians, per-frame time, and the ratios run/bare, pinned/bare (the goal is
// <= 1.5) and device/bare (the bare transforms move no data over the bus, while Run must
// bring 64 KiB per frame in and the GCC windows out). The CPU estimator's time per frame on
// one core is printed for scale.
//
// The frame bytes over the bus per frame, whole and through the ring, are host arithmetic and
// printed first, with or without a device (GccBatch::last_frame_bytes_over_bus confirms them
// on the device). Without a usable device it then prints why and exits 0. Run:
//   build/tests/bench/gpu_gcc_bench [repetitions, default 30]

// Eigen's CUDA support is for device code; this file uses Eigen on the host only.
#define EIGEN_NO_CUDA
// nvcc's front end flags engine/core/status.h's assignment of a [[nodiscard]] Status to a
// member as "ignoring return value" (g++ does not); the engine code is fine.
#pragma nv_diag_suppress 2810

#include <cuda_runtime_api.h>
#include <cufft.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "engine/tdoa/gcc_phat.h"
#include "gpu/core/cuda_status.h"
#include "gpu/core/device.h"
#include "gpu/tdoa/gcc_batch.h"
#include "gpu/tdoa/sample_ring.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::gpu {
namespace {

constexpr int kChannels = 4;
constexpr int kFrameSamples = 4096;
constexpr double kSampleRateHz = 44100.0;
constexpr int kDistinctFrames = 16;      // cycled through larger batches
constexpr int kHop = kFrameSamples / 2;  // the ring's 50 % hop
constexpr std::size_t kWholeFrameBytes = sizeof(float) * kChannels * kFrameSamples;
constexpr std::size_t kRingFrameBytes = sizeof(float) * kChannels * kHop;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// One R2C and one C2R, batched as GccBatch batches them, on buffers of its own. (Raw CUDA
// handles: nvcc's front end rejects device_buffer.h's `return s;` of move-only types.)
class BareFft {
 public:
  static StatusOr<std::unique_ptr<BareFft>> Create(int n, int frames) {
    std::unique_ptr<BareFft> bare(new BareFft());
    const std::size_t floats = static_cast<std::size_t>(frames) * kChannels * 2 * (n / 2 + 1);
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaStreamCreateWithFlags(&bare->stream_, cudaStreamNonBlocking),
                                   "cudaStreamCreate");
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMalloc(&bare->real_, sizeof(float) * floats), "cudaMalloc");
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMalloc(&bare->complex_, sizeof(float) * floats), "cudaMalloc");
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMemset(bare->real_, 0, sizeof(float) * floats), "cudaMemset");
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMemset(bare->complex_, 0, sizeof(float) * floats), "cudaMemset");
    LOCALIZER_CUFFT_RETURN_IF_ERROR(cufftPlan1d(&bare->forward_, n, CUFFT_R2C, frames * kChannels), "cufftPlan1d(R2C)");
    LOCALIZER_CUFFT_RETURN_IF_ERROR(cufftPlan1d(&bare->inverse_, n, CUFFT_C2R, frames * (kChannels - 1)),
                                    "cufftPlan1d(C2R)");
    LOCALIZER_CUFFT_RETURN_IF_ERROR(cufftSetStream(bare->forward_, bare->stream_), "cufftSetStream");
    LOCALIZER_CUFFT_RETURN_IF_ERROR(cufftSetStream(bare->inverse_, bare->stream_), "cufftSetStream");
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventCreate(&bare->start_), "cudaEventCreate");
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventCreate(&bare->end_), "cudaEventCreate");
    return StatusOr<std::unique_ptr<BareFft>>(std::move(bare));
  }
  ~BareFft() {
    if (forward_ != CUFFT_PLAN_NULL) cufftDestroy(forward_);
    if (inverse_ != CUFFT_PLAN_NULL) cufftDestroy(inverse_);
    if (start_ != nullptr) cudaEventDestroy(start_);
    if (end_ != nullptr) cudaEventDestroy(end_);
    if (real_ != nullptr) cudaFree(real_);
    if (complex_ != nullptr) cudaFree(complex_);
    if (stream_ != nullptr) cudaStreamDestroy(stream_);
  }
  BareFft(const BareFft&) = delete;
  BareFft& operator=(const BareFft&) = delete;

  // Milliseconds of device time for the two executions.
  StatusOr<float> Run() {
    auto* complex = reinterpret_cast<cufftComplex*>(complex_);
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventRecord(start_, stream_), "cudaEventRecord");
    LOCALIZER_CUFFT_RETURN_IF_ERROR(cufftExecR2C(forward_, real_, complex), "cufftExecR2C");
    LOCALIZER_CUFFT_RETURN_IF_ERROR(cufftExecC2R(inverse_, complex, real_), "cufftExecC2R");
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventRecord(end_, stream_), "cudaEventRecord");
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
    float ms = 0.0f;
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventElapsedTime(&ms, start_, end_), "cudaEventElapsedTime");
    return ms;
  }

 private:
  BareFft() = default;
  cudaStream_t stream_ = nullptr;
  float* real_ = nullptr;
  float* complex_ = nullptr;
  cufftHandle forward_ = CUFFT_PLAN_NULL;
  cufftHandle inverse_ = CUFFT_PLAN_NULL;
  cudaEvent_t start_ = nullptr;
  cudaEvent_t end_ = nullptr;
};

struct Row {
  int frames = 0;
  double run_wall_ms = 0.0;
  double run_total_ms = 0.0;
  double run_device_ms = 0.0;
  double run_fft_ms = 0.0;
  double bare_ms = 0.0;
  double pinned_wall_ms = 0.0;
  double ring_wall_ms = 0.0;
  double ring_total_ms = 0.0;
  double ring_bytes_per_frame = 0.0;
};

int Fail(const Status& status) {
  std::fprintf(stderr, "gpu_gcc_bench: %s\n", status.ToString().c_str());
  return 1;
}

int Main(int repetitions) {
  std::printf(
      "Frame bytes over the bus per frame (%d channels x %d float samples): whole %zu, ring at a 50 %% hop "
      "%zu (x%.2f); 1024 frames: %.1f MiB -> %.1f MiB\n",
      kChannels, kFrameSamples, kWholeFrameBytes, kRingFrameBytes,
      static_cast<double>(kRingFrameBytes) / kWholeFrameBytes, 1024.0 * kWholeFrameBytes / (1 << 20),
      1024.0 * kRingFrameBytes / (1 << 20));
  if (const std::string& reason = DeviceUnavailableReason(); !reason.empty()) {
    std::printf("gpu_gcc_bench: no usable GPU (%s); nothing measured.\n", reason.c_str());
    return 0;
  }
  const engine::ArrayGeometry array = *engine::ArrayGeometry::Create(engine::testing::TetrahedronSensors(), 1500.0);
  engine::GccOptions options;
  options.frame_samples = kFrameSamples;
  options.sample_rate_hz = kSampleRateHz;
  options.band_low_hz = 200.0;
  options.band_high_hz = 0.4 * kSampleRateHz;
  auto plan = GccPlan::Create(array, options);
  if (!plan.ok()) return Fail(plan.status());

  engine::testing::SignalSpec spec;
  spec.sample_rate_hz = kSampleRateHz;
  spec.band_low_hz = options.band_low_hz;
  spec.band_high_hz = options.band_high_hz;
  spec.frame_samples = kFrameSamples;
  std::vector<std::vector<float>> frames;
  for (int i = 0; i < kDistinctFrames; ++i) {
    const auto delays = engine::testing::ChannelDelaysSamples(array, engine::Vec3(12.0 + i, -30.0, 4.0), kSampleRateHz);
    frames.push_back(engine::testing::DelayedNoiseFrame(spec, delays, 20.0, 42 + i));
  }

  // The CPU stage per frame, for scale.
  auto cpu = engine::GccPhatEstimator::Create(array, options);
  if (!cpu.ok()) return Fail(cpu.status());
  std::vector<double> cpu_us;
  engine::Measurement m;
  for (int i = 0; i < 200; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const Status s = (*cpu)->Estimate(frames[i % kDistinctFrames].data(), kFrameSamples, 0.0, &m);
    const auto t1 = std::chrono::steady_clock::now();
    if (!s.ok()) return Fail(s);
    cpu_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }

  std::vector<Row> rows;
  for (int count : {1, 16, 256, 1024}) {
    auto batch = GccBatch::Create(plan->key(), count, /*collect_timing=*/true);
    if (!batch.ok()) return Fail(batch.status());
    auto bare = BareFft::Create(plan->layout().fft_size, count);
    if (!bare.ok()) return Fail(bare.status());
    std::vector<engine::Measurement> out(count);
    std::vector<GccJob> jobs, pinned_jobs;
    for (int j = 0; j < count; ++j) jobs.push_back({&*plan, frames[j % kDistinctFrames].data(), 0.0, &out[j]});
    // Each job's own pinned copy of its frame, as sessions keep them.
    const std::size_t frame_floats = static_cast<std::size_t>(kChannels) * kFrameSamples;
    float* pinned = nullptr;
    if (const Status s = FromCuda(cudaMallocHost(&pinned, sizeof(float) * frame_floats * count), "cudaMallocHost");
        !s.ok()) {
      return Fail(s);
    }
    std::unique_ptr<float, cudaError_t (*)(void*)> pinned_owner(pinned, cudaFreeHost);
    for (int j = 0; j < count; ++j) {
      std::copy_n(frames[j % kDistinctFrames].data(), frame_floats, pinned + j * frame_floats);
      pinned_jobs.push_back({&*plan, pinned + j * frame_floats, 0.0, &out[j]});
      pinned_jobs.back().frame_pinned = true;
    }
    // The ring jobs: pinned frames whose channels repeat their first half, one ring each;
    // the first Run (a warm-up round) fills the rings with whole frames.
    float* periodic = nullptr;
    if (const Status s = FromCuda(cudaMallocHost(&periodic, sizeof(float) * frame_floats * count), "cudaMallocHost");
        !s.ok()) {
      return Fail(s);
    }
    std::unique_ptr<float, cudaError_t (*)(void*)> periodic_owner(periodic, cudaFreeHost);
    std::vector<SampleRing> rings;
    std::vector<GccJob> ring_jobs;
    for (int j = 0; j < count; ++j) {
      float* frame = periodic + j * frame_floats;
      for (int c = 0; c < kChannels; ++c) {
        const float* half = frames[j % kDistinctFrames].data() + static_cast<std::size_t>(c) * kFrameSamples;
        std::copy_n(half, kHop, frame + c * kFrameSamples);
        std::copy_n(half, kHop, frame + c * kFrameSamples + kHop);
      }
      auto ring = SampleRing::Create(kChannels, kFrameSamples);
      if (!ring.ok()) return Fail(ring.status());
      rings.push_back(std::move(ring).value());
      ring_jobs.push_back({&*plan, frame, 0.0, &out[j]});
      ring_jobs.back().frame_pinned = true;
    }

    std::vector<double> wall, total, device, fft, bare_ms, pinned_wall, ring_wall, ring_total;
    std::size_t ring_bytes = 0;
    for (int r = -3; r < repetitions; ++r) {  // 3 warm-up rounds
      const auto t0 = std::chrono::steady_clock::now();
      const Status s = (*batch)->Run(jobs);
      const auto t1 = std::chrono::steady_clock::now();
      if (!s.ok()) return Fail(s);
      auto b = (*bare)->Run();
      if (!b.ok()) return Fail(b.status());
      const auto t2 = std::chrono::steady_clock::now();
      const Status sp = (*batch)->Run(pinned_jobs);
      const auto t3 = std::chrono::steady_clock::now();
      if (!sp.ok()) return Fail(sp);
      // The events of the last Run before reading them: the pinned one's (as before the ring
      // columns were added; the header's "its CUDA event times" of `run` says otherwise).
      const GccBatch::Timing t = (*batch)->last_timing();
      for (int j = 0; j < count; ++j) {
        ring_jobs[j].ring = &rings[j];
        ring_jobs[j].ring_new_samples = rings[j].valid() ? kHop : kFrameSamples;
      }
      const auto t4 = std::chrono::steady_clock::now();
      const Status sr = (*batch)->Run(ring_jobs);
      const auto t5 = std::chrono::steady_clock::now();
      if (!sr.ok()) return Fail(sr);
      if (r < 0) continue;
      ring_wall.push_back(std::chrono::duration<double, std::milli>(t5 - t4).count());
      ring_total.push_back((*batch)->last_timing().total_ms);
      ring_bytes = (*batch)->last_frame_bytes_over_bus();
      pinned_wall.push_back(std::chrono::duration<double, std::milli>(t3 - t2).count());
      wall.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      total.push_back(t.total_ms);
      device.push_back(t.device_ms);
      fft.push_back(t.fft_ms);
      bare_ms.push_back(*b);
    }
    rows.push_back({count, Median(wall), Median(total), Median(device), Median(fft), Median(bare_ms),
                    Median(pinned_wall), Median(ring_wall), Median(ring_total),
                    static_cast<double>(ring_bytes) / count});
  }

  std::printf("GPU GCC-PHAT batch, %s; %d channels x %d samples at %.0f Hz, N = %d; medians of %d\n",
              Device().name.c_str(), kChannels, kFrameSamples, kSampleRateHz, plan->layout().fft_size, repetitions);
  std::printf("CPU GccPhatEstimator::Estimate: %.1f us per frame (one core)\n\n", Median(cpu_us));
  std::printf("%7s %10s %10s %10s %10s %10s %10s %10s %9s %11s %11s\n", "frames", "run ms", "us/frame", "pinned ms",
              "events ms", "device ms", "in-run fft", "bare fft", "run/bare", "pinned/bare", "device/bare");
  for (const Row& r : rows) {
    std::printf("%7d %10.3f %10.2f %10.3f %10.3f %10.3f %10.3f %10.3f %9.2f %11.2f %11.2f\n", r.frames, r.run_wall_ms,
                1000.0 * r.run_wall_ms / r.frames, r.pinned_wall_ms, r.run_total_ms, r.run_device_ms, r.run_fft_ms,
                r.bare_ms, r.run_wall_ms / r.bare_ms, r.pinned_wall_ms / r.bare_ms, r.run_device_ms / r.bare_ms);
  }
  std::printf("\nThrough the device rings (50 %% hop, pinned frames; goal ring/bare <= 1.5):\n");
  std::printf("%7s %14s %10s %10s %10s %9s %12s\n", "frames", "bytes/frame", "ring ms", "pinned ms", "events ms",
              "ring/bare", "ring/pinned");
  for (const Row& r : rows) {
    std::printf("%7d %14.0f %10.3f %10.3f %10.3f %9.2f %12.2f\n", r.frames, r.ring_bytes_per_frame, r.ring_wall_ms,
                r.pinned_wall_ms, r.ring_total_ms, r.ring_wall_ms / r.bare_ms, r.ring_wall_ms / r.pinned_wall_ms);
  }
  return 0;
}

}  // namespace
}  // namespace localizer::gpu

int main(int argc, char** argv) {
  const int repetitions = argc > 1 ? std::max(1, std::atoi(argv[1])) : 30;
  return localizer::gpu::Main(repetitions);
}
