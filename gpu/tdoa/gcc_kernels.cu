// The kernels of the batched GCC-PHAT stage (see gcc_kernels.h for what each computes; the
// per-bin and per-window maths are the CPU stage's own, engine/tdoa/gcc_math.h and
// peak_math.h, through gcc_math.cuh). Deterministic by construction:
// one block owns each output row, every sum is a cub::BlockReduce of a fixed block size
// (fixed order), the argmax combines (value, index) pairs by an order-independent rule, and
// maxima of |R| are exact whatever the order. No atomics.
// nvcc's front end flags engine/core/status.h's assignment of a [[nodiscard]] Status to a
// member as "ignoring return value" (g++ does not); the engine code is fine.
#pragma nv_diag_suppress 2810
#include <cstddef>
#include <cub/block/block_reduce.cuh>

#include "engine/tdoa/delay_statistics.h"
#include "gpu/core/cuda_status.h"
#include "gpu/tdoa/frame_sources.cuh"
#include "gpu/tdoa/gcc_kernels.h"
#include "gpu/tdoa/gcc_math.cuh"

namespace localizer::gpu {
namespace {

constexpr int kPackThreads = 256;
constexpr int kAppendThreads = 256;
constexpr int kWeighThreads = 256;
constexpr int kPeakThreads = 128;  // windows are a few hundred lags; 4 warps read them
constexpr int kMomentThreads = 256;

__global__ void __launch_bounds__(kPackThreads) GccPackKernel(GccPackArgs a) {
  using Reduce = cub::BlockReduce<double, kPackThreads>;
  __shared__ typename Reduce::TempStorage scratch;
  const int row = blockIdx.x;
  const bool live = row < a.live_rows;
  // Rows past the live ones are the bucket's padding frames: zeros, and no frame to read.
  GccFrameSource source;
  if (live) source = a.sources[row / a.channels];
  const int channel = row % a.channels;
  float* out = a.signal + static_cast<std::size_t>(row) * a.fft_size;
  double energy = 0.0;
  for (int i = threadIdx.x; i < a.fft_size; i += kPackThreads) {
    const float v = (live && i < a.frame_samples)
                        ? *FrameSample(source, channel, i) * engine::TaperGain(i, a.frame_samples, source.taper_edge)
                        : 0.0f;
    out[i] = v;
    energy += static_cast<double>(v) * v;
  }
  energy = Reduce(scratch).Sum(energy);
  if (threadIdx.x == 0) a.energy[row] = energy;
}

__global__ void __launch_bounds__(kAppendThreads) GccRingAppendKernel(GccAppendArgs a) {
  const GccRingAppend p = a.appends[blockIdx.x / a.channels];
  const int channel = blockIdx.x % a.channels;
  for (int i = threadIdx.x; i < p.count; i += kAppendThreads) *AppendTo(p, channel, i) = *AppendFrom(p, channel, i);
}

__global__ void __launch_bounds__(kWeighThreads) GccWeighKernel(GccWeighArgs a) {
  using Reduce = cub::BlockReduce<double, kWeighThreads>;
  __shared__ typename Reduce::TempStorage scratch;
  __shared__ float edge_re[2];  // Re G at DC and at Nyquist
  const int task = blockIdx.x;
  const GccPairTask t = a.tasks[task];
  const int bins = a.fft_size / 2 + 1;
  const double e_ref = a.energy[t.ref_row];
  const double e_sensor = a.energy[t.sensor_row];
  const gcc::WeighParams params = gcc::MakeWeighParams(t.weighting, t.beta, e_ref, e_sensor);
  const float2* xr = reinterpret_cast<const float2*>(a.spectra) + static_cast<std::size_t>(t.ref_row) * bins;
  const float2* xk = reinterpret_cast<const float2*>(a.spectra) + static_cast<std::size_t>(t.sensor_row) * bins;
  float2* g = reinterpret_cast<float2*>(a.cross) + static_cast<std::size_t>(task) * bins;
  if (threadIdx.x == 0) edge_re[0] = edge_re[1] = 0.0f;
  __syncthreads();

  double half_sum = 0.0;
  for (int b = threadIdx.x; b < bins; b += kWeighThreads) {
    float2 out = make_float2(0.0f, 0.0f);
    if (b >= t.band_first_bin && b < t.band_end_bin) {
      const float2 r = xr[b];
      const float2 k = xk[b];
      const gcc::WeighedBin w = gcc::WeighBin(params, {r.x, r.y}, {k.x, k.y});
      out = make_float2(w.g.re, w.g.im);
      half_sum += w.weighted_mag;
    }
    g[b] = out;
    if (b == 0) edge_re[0] = out.x;
    if (b == bins - 1) edge_re[1] = out.x;
  }
  half_sum = Reduce(scratch).Sum(half_sum);
  __syncthreads();  // edge_re written by whichever threads held bins 0 and N/2
  if (threadIdx.x == 0) {
    GccPairResult& r = a.results[task];
    r.norm = gcc::FullSpectrumNorm(half_sum, edge_re[0], edge_re[1]);
    r.energy_ref = e_ref;
    r.energy_sensor = e_sensor;
  }
}

struct BetterPeakOp {
  __device__ gcc::PeakCandidate operator()(const gcc::PeakCandidate& a, const gcc::PeakCandidate& b) const {
    return gcc::BetterPeak(a, b);
  }
};

struct MaxOp {
  __device__ float operator()(float a, float b) const { return engine::hd::Max(a, b); }
};

// Thread 0 finds the main lobe while thread kRefineThread (another warp) refines the peak.
constexpr int kRefineThread = 32;

__global__ void __launch_bounds__(kPeakThreads) GccPeakKernel(GccPeakArgs a) {
  using ArgMax = cub::BlockReduce<gcc::PeakCandidate, kPeakThreads>;
  using MaxAbs = cub::BlockReduce<float, kPeakThreads>;
  __shared__ union {
    typename ArgMax::TempStorage argmax;
    typename MaxAbs::TempStorage max_abs;
  } scratch;
  __shared__ gcc::PeakCandidate peak;
  __shared__ int lobe_first;  // window indices (window mode) or lags (circular mode)
  __shared__ int lobe_last;
  __shared__ bool circular;  // the lobe filled the window: sidelobe from the full corr
  __shared__ double offset;
  __shared__ double floor_samples;

  const int task = blockIdx.x;
  const GccPairTask t = a.tasks[task];
  const int n = a.fft_size;
  const int max_lag = t.max_lag;
  const int count = 2 * max_lag + 1;  // window index i is lag i - max_lag
  const float* corr = a.corr + static_cast<std::size_t>(task) * n;
  float* window_out = t.gcc_offset >= 0 ? a.gcc + t.gcc_offset : nullptr;
  GccPairResult& result = a.results[task];
  const float norm = result.norm;

  constexpr int K = engine::kPeakHalfWidth;
  const int kept = count + 2 * K;  // the window out holds lags -(L + K)..L + K

  if (!(norm > 0.0f)) {  // no energy in the band: nothing to measure (uniform branch)
    if (window_out != nullptr) {
      for (int i = threadIdx.x; i < kept; i += kPeakThreads) window_out[i] = 0.0f;
    }
    if (threadIdx.x == 0) {
      result.offset_samples = 0.0;
      result.peak_value = 0.0f;
      result.quality = 0.0f;
      result.peak_lag = 0;
      result.floor_samples = 0.0;
    }
    return;
  }
  const float scale = 1.0f / norm;
  const auto scaled = [&](int lag) { return corr[engine::WrapLag(lag, n)] * scale; };
  const auto in_window = [&](int i) { return scaled(i - max_lag); };

  // 1. The first maximum of R over the window; the window to the gcc output on the way.
  if (window_out != nullptr) {
    for (int i = threadIdx.x; i < kept; i += kPeakThreads) window_out[i] = in_window(i - K);
  }
  gcc::PeakCandidate best = gcc::NoPeak();
  for (int i = threadIdx.x; i < count; i += kPeakThreads) best = gcc::BetterPeak(best, {in_window(i), i});
  best = ArgMax(scratch.argmax).Reduce(best, BetterPeakOp());
  if (threadIdx.x == 0) peak = best;
  __syncthreads();
  const int peak_lag = peak.index - max_lag;

  // 2. The main lobe (thread 0) and the sub-sample refinement (another warp), side by side.
  if (threadIdx.x == 0) {
    int first = 0;
    int last = 0;
    engine::MainLobe(in_window, count, peak.index, &first, &last);
    circular = !(first > 0 || last + 1 < count);
    if (circular) {  // unscaled, as the CPU walks it
      const auto raw = [&](int lag) { return corr[engine::WrapLag(lag, n)]; };
      engine::CircularMainLobe(raw, n, peak_lag, &first, &last);
    }
    lobe_first = first;
    lobe_last = last;
  }
  if (threadIdx.x == kRefineThread % kPeakThreads) {
    float samples[engine::kPeakSamples];
    for (int m = 0; m < engine::kPeakSamples; ++m) samples[m] = scaled(peak_lag + m - engine::kPeakHalfWidth);
    offset = gcc::InterpolatePeak(t.interpolation, samples);
    // engine::InterpolationErrorSamples: kSinc's floor, or the others' distance from kSinc.
    floor_samples = engine::kSincFloorSamples;
    if (t.interpolation != gcc::kSinc) {
      const double bias = offset - gcc::InterpolatePeak(gcc::kSinc, samples);
      floor_samples = sqrt(bias * bias + engine::kSincFloorSamples * engine::kSincFloorSamples);
    }
  }
  __syncthreads();

  // 3. The largest |R| outside the lobe: in the window, or over the rest of the circle.
  float sidelobe = 0.0f;
  if (!circular) {
    for (int i = threadIdx.x; i < count; i += kPeakThreads) {
      if (i < lobe_first || i > lobe_last) sidelobe = engine::hd::Max(sidelobe, fabsf(in_window(i)));
    }
  } else {
    for (int lag = lobe_last + 1 + threadIdx.x; lag < lobe_first + n; lag += kPeakThreads) {
      sidelobe = engine::hd::Max(sidelobe, fabsf(corr[engine::WrapLag(lag, n)]));
    }
  }
  sidelobe = MaxAbs(scratch.max_abs).Reduce(sidelobe, MaxOp());
  if (threadIdx.x == 0) {
    if (circular) sidelobe = scale * sidelobe;
    result.peak_lag = peak_lag;
    result.offset_samples = offset;
    result.peak_value = peak.value;
    result.quality = engine::QualityRatio(peak.value, sidelobe);
    result.floor_samples = floor_samples;
  }
}

__global__ void __launch_bounds__(kMomentThreads) GccMomentsKernel(GccMomentsArgs a) {
  using Reduce = cub::BlockReduce<double, kMomentThreads>;
  __shared__ typename Reduce::TempStorage scratch;
  const int task = blockIdx.x;
  const GccPairTask t = a.tasks[task];
  GccPairResult& result = a.results[task];
  if (!(result.norm > 0.0f)) return;  // nothing measured (uniform branch)
  const int bins = a.fft_size / 2 + 1;
  const gcc::WeighParams params = gcc::MakeWeighParams(t.weighting, t.beta, result.energy_ref, result.energy_sensor);
  const float2* xr = reinterpret_cast<const float2*>(a.spectra) + static_cast<std::size_t>(t.ref_row) * bins;
  const float2* xk = reinterpret_cast<const float2*>(a.spectra) + static_cast<std::size_t>(t.sensor_row) * bins;
  const double delay_samples = result.peak_lag + result.offset_samples;
  gcc::BinMoments m;
  for (int b = t.band_first_bin + static_cast<int>(threadIdx.x); b < t.band_end_bin; b += kMomentThreads) {
    const float2 r = xr[b];
    const float2 k = xk[b];
    gcc::AddBinMoments(b, a.fft_size, delay_samples, gcc::WeighBin(params, {r.x, r.y}, {k.x, k.y}).g, &m);
  }
  // Four sums through one TempStorage: a barrier between reductions lets it be reused.
  const double level = Reduce(scratch).Sum(m.level);
  __syncthreads();
  const double first = Reduce(scratch).Sum(m.first);
  __syncthreads();
  const double curvature = Reduce(scratch).Sum(m.curvature);
  __syncthreads();
  const double slope_var = Reduce(scratch).Sum(m.slope_var);
  if (threadIdx.x == 0) {
    result.level = level;
    result.first = first;
    result.curvature = curvature;
    result.slope_var = slope_var;
  }
}

}  // namespace

Status LaunchGccMoments(const GccMomentsArgs& args, cudaStream_t stream) {
  if (args.task_count == 0) return Status::Ok();
  GccMomentsKernel<<<args.task_count, kMomentThreads, 0, stream>>>(args);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("GccMomentsKernel");
  return Status::Ok();
}

Status LaunchGccPack(const GccPackArgs& args, cudaStream_t stream) {
  if (args.rows == 0) return Status::Ok();
  GccPackKernel<<<args.rows, kPackThreads, 0, stream>>>(args);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("GccPackKernel");
  return Status::Ok();
}

Status LaunchGccRingAppend(const GccAppendArgs& args, cudaStream_t stream) {
  if (args.append_count == 0) return Status::Ok();
  GccRingAppendKernel<<<args.append_count * args.channels, kAppendThreads, 0, stream>>>(args);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("GccRingAppendKernel");
  return Status::Ok();
}

Status LaunchGccWeigh(const GccWeighArgs& args, cudaStream_t stream) {
  if (args.task_count == 0) return Status::Ok();
  GccWeighKernel<<<args.task_count, kWeighThreads, 0, stream>>>(args);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("GccWeighKernel");
  return Status::Ok();
}

Status LaunchGccPeak(const GccPeakArgs& args, cudaStream_t stream) {
  if (args.task_count == 0) return Status::Ok();
  GccPeakKernel<<<args.task_count, kPeakThreads, 0, stream>>>(args);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("GccPeakKernel");
  return Status::Ok();
}

}  // namespace localizer::gpu
