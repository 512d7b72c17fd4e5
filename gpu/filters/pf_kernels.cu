// The particle bank's kernels (see pf_kernels.h for the sequence and its invariants).
//
// Determinism: no atomics; every reduction is a fixed tree over a fixed block size
// (kBlockThreads threads, out-of-range threads contributing the identity), and the
// per-session passes walk only that session's blocks, in a fixed order. Random numbers are
// Philox, keyed by (seed, particle index, draw window): a session's results depend only on
// its own inputs and history.
// nvcc's front end flags engine/core/status.h's assignment of a [[nodiscard]] Status to a
// member as "ignoring return value" (g++ does not), as in gcc_kernels.cu.
#pragma nv_diag_suppress 2810
#include <curand_kernel.h>
#include <math_constants.h>

#include <cub/block/block_scan.cuh>

#include "gpu/core/cuda_status.h"
#include "gpu/filters/pf_kernels.h"
#include "gpu/filters/pf_math.cuh"

namespace localizer::gpu::pf {
namespace {

constexpr int kWarps = kBlockThreads / 32;
static_assert(kBlockThreads % 32 == 0 && kBlockThreads <= 1024, "whole warps per block");
static_assert(kWeighedSums == kMomentSums, "moment sums: one count");
using BlockScan = cub::BlockScan<double, kBlockThreads>;

struct SumOp {
  template <typename T>
  __device__ __forceinline__ T operator()(T a, T b) const {
    return a + b;
  }
};
struct MaxOp {
  __device__ __forceinline__ float operator()(float a, float b) const { return fmaxf(a, b); }
};

// Lane 0 of each warp gets op over the warp's 32 values (a fixed tree).
template <typename T, typename Op>
__device__ __forceinline__ T WarpReduce(T v, Op op) {
#pragma unroll
  for (int offset = 16; offset > 0; offset >>= 1) v = op(v, __shfl_down_sync(0xffffffffu, v, offset));
  return v;
}

// op over the block of each of the K values every thread holds; the results land in
// `total` (shared, K entries) for every thread. Every thread of the block must call it.
// warp_scratch: shared, kWarps * K entries.
template <typename T, int K, typename Op>
__device__ void BlockReduceShuffle(T (&v)[K], Op op, T* warp_scratch, T* total) {
  const int lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
#pragma unroll
  for (int k = 0; k < K; ++k) v[k] = WarpReduce(v[k], op);
  if (lane == 0) {
#pragma unroll
    for (int k = 0; k < K; ++k) warp_scratch[warp * K + k] = v[k];
  }
  __syncthreads();
  for (int k = threadIdx.x; k < K; k += kBlockThreads) {
    T t = warp_scratch[k];
    for (int w = 1; w < kWarps; ++w) t = op(t, warp_scratch[w * K + k]);
    total[k] = t;
  }
  __syncthreads();
}

// Block sums of K floats per thread through a transposed shared array (rows: K x
// kBlockThreads): each warp sums whole rows, cheaper than K shuffle trees for large K.
// Results in `total` (shared, K entries) for every thread; every thread must call it.
template <int K>
__device__ void BlockSumRows(const float (&v)[K], float* rows, float* total) {
#pragma unroll
  for (int k = 0; k < K; ++k) rows[k * kBlockThreads + threadIdx.x] = v[k];
  __syncthreads();
  const int lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
  for (int row = warp; row < K; row += kWarps) {
    float t = 0.0f;
    for (int j = 0; j < kBlockThreads / 32; ++j) t += rows[row * kBlockThreads + j * 32 + lane];
    t = WarpReduce(t, SumOp());
    if (lane == 0) total[row] = t;
  }
  __syncthreads();
}

// Philox normals: four from the window's values [offset, offset + 4).
__device__ __forceinline__ float4 Normals4(unsigned long long seed, unsigned long long subsequence,
                                           unsigned long long offset) {
  curandStatePhilox4_32_10_t state;
  curand_init(seed, subsequence, offset, &state);
  return curand_normal4(&state);
}

// The inclusive cumulative weight of particle j of a resampling session: its block's
// offset plus its within-block prefix sum.
struct Cumulative {
  const double* local;
  const BlockPartial* partials;
  __host__ __device__ double operator()(int j) const { return partials[j / kBlockThreads].w_offset + local[j]; }
};

// 1. Predict, weigh, per-block partials.
__global__ void __launch_bounds__(kBlockThreads)
    WeighKernel(const SessionStep* __restrict__ steps, const int* __restrict__ block_request,
                const float* __restrict__ gcc) {
  __shared__ float warp_scratch[kWarps * 2];
  __shared__ float total[2];
  const SessionStep& s = steps[block_request[blockIdx.x]];
  const int local_block = static_cast<int>(blockIdx.x) - s.first_block;
  const int i = local_block * kBlockThreads + static_cast<int>(threadIdx.x);
  const bool valid = i < s.slot.particles;
  float x[6] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
  if (valid) {
#pragma unroll
    for (int c = 0; c < 6; ++c) x[c] = s.slot.state[c][i];
  }
  if (s.do_predict && valid) {
    const float4 a = Normals4(s.seed, static_cast<unsigned long long>(i), s.draw * kDrawWindow);
    const float g = a.w < s.manoeuvre_z ? s.manoeuvre_gain : s.quiet_gain;  // ParticleFilterOptions::manoeuvre_share
    PredictParticle(x, s.dt, s.a_to_p, s.a_to_v, g * a.x, g * a.y, g * a.z);
#pragma unroll
    for (int c = 0; c < 6; ++c) s.slot.state[c][i] = x[c];
  }
  if (!s.do_update) return;  // uniform over the block: one session per block

  BlockPartial& part = s.slot.partials[local_block];
  const float w_prior = valid ? s.slot.w[i] : 0.0f;
  const RangeRate ref = RangeAndRate(x, s.reference[0], s.reference[1], s.reference[2]);
  float ll = 0.0f;
  for (int p = 0; p < s.pairs; ++p) {
    const PairParams& pp = s.pair[p];
    if (!pp.used) {
      if (threadIdx.x == 0) part.sum_e[p] = part.sum_e2[p] = 0.0f;
      continue;
    }
    const RangeRate rk = RangeAndRate(x, pp.sensor[0], pp.sensor[1], pp.sensor[2]);
    const float h = PairDelay(rk, ref, pp.half_delay_s, s.inv_c);
    const float e = (pp.delay_s - h) * pp.inv_sigma;
    if (pp.gcc_offset >= 0) {
      ll += pp.gcc_gain *
            engine::CatmullRomRead(gcc + pp.gcc_offset, engine::GccFineLag(h, pp.lag_scale, pp.lag0), pp.last_lag);
    } else if (pp.blur_var_s2 > 0.0f) {
      // Motion blur: this particle's delay rate widens the pair's likelihood (the engine's
      // ParticleSet::Weigh).
      const float rate = (rk.vr - ref.vr) * s.inv_c * pp.inv_sigma;
      const float widen = 1.0f + pp.blur_var_s2 * rate * rate;
      ll += StudentTLogLikelihood(e * rsqrtf(widen), s.inv_dof, s.half_dof_plus_1) - 0.5f * logf(widen);
    } else {
      ll += StudentTLogLikelihood(e, s.inv_dof, s.half_dof_plus_1);
    }
    float v[2] = {w_prior * e, w_prior * e * e};
    BlockReduceShuffle(v, SumOp(), warp_scratch, total);
    if (threadIdx.x == 0) {
      part.sum_e[p] = total[0];
      part.sum_e2[p] = total[1];
    }
  }
  float lw = -CUDART_INF_F;
  if (valid) {
    lw = s.slot.logw[i] + ll;
    s.slot.logw[i] = lw;
  }
  float m[1] = {lw};
  BlockReduceShuffle(m, MaxOp(), warp_scratch, total);
  const float max_logw = total[0];
  __syncthreads();  // everyone has read total[0] before it is reused
  const float u = valid ? expf(lw - max_logw) : 0.0f;
  float v[2] = {u, u * u};
  BlockReduceShuffle(v, SumOp(), warp_scratch, total);
  if (threadIdx.x == 0) {
    part.max_logw = max_logw;
    part.sum_u = total[0];
    part.sum_u2 = total[1];
  }
}

// 2. Per session: log-sum-exp, ESS, resampling decision, innovation sums.
__global__ void __launch_bounds__(kBlockThreads)
    SessionWeightsKernel(const SessionStep* __restrict__ steps, SessionWork* __restrict__ work,
                         StepOutput* __restrict__ out) {
  constexpr int kSums = 2 + 2 * kMaxPairs;
  __shared__ float fscratch[kWarps];
  __shared__ float ftotal[1];
  __shared__ double dscratch[kWarps * kSums];
  __shared__ double dtotal[kSums];
  const SessionStep& s = steps[blockIdx.x];
  SessionWork& wk = work[blockIdx.x];
  StepOutput& o = out[blockIdx.x];
  if (!s.do_update) {
    if (threadIdx.x == 0) {
      wk.max_logw = 0.0f;
      wk.inv_sum = 1.0f;
      wk.log_norm = 0.0f;
      wk.resample = 0;
      wk.u0 = 0.0;
      o.ess = s.prior_ess;
      o.resampled = 0;
      for (int p = 0; p < kMaxPairs; ++p) o.sum_e[p] = o.sum_e2[p] = 0.0;
    }
    return;
  }
  const BlockPartial* parts = s.slot.partials;
  const int blocks = s.slot.blocks;
  float m[1] = {-CUDART_INF_F};
  for (int b = threadIdx.x; b < blocks; b += kBlockThreads) m[0] = fmaxf(m[0], parts[b].max_logw);
  BlockReduceShuffle(m, MaxOp(), fscratch, ftotal);
  const double max_logw = ftotal[0];
  double acc[kSums];
#pragma unroll
  for (int k = 0; k < kSums; ++k) acc[k] = 0.0;
  for (int b = threadIdx.x; b < blocks; b += kBlockThreads) {
    const BlockPartial& q = parts[b];
    const double scale = exp(static_cast<double>(q.max_logw) - max_logw);
    acc[0] += static_cast<double>(q.sum_u) * scale;
    acc[1] += static_cast<double>(q.sum_u2) * scale * scale;
#pragma unroll
    for (int p = 0; p < kMaxPairs; ++p) {
      if (p < s.pairs) {
        acc[2 + p] += q.sum_e[p];
        acc[2 + kMaxPairs + p] += q.sum_e2[p];
      }
    }
  }
  BlockReduceShuffle(acc, SumOp(), dscratch, dtotal);
  if (threadIdx.x != 0) return;
  const double sum = dtotal[0], sum_sq = dtotal[1];
  const double ess = sum * sum / sum_sq;
  const int resample = ess < s.resample_below ? 1 : 0;
  o.ess = ess;
  o.resampled = resample;
  for (int p = 0; p < kMaxPairs; ++p) {
    o.sum_e[p] = dtotal[2 + p];
    o.sum_e2[p] = dtotal[2 + kMaxPairs + p];
  }
  wk.max_logw = static_cast<float>(max_logw);
  wk.inv_sum = static_cast<float>(1.0 / sum);
  wk.log_norm = static_cast<float>(max_logw + log(sum));
  wk.resample = resample;
  wk.u0 = 0.0;
  if (resample) {
    curandStatePhilox4_32_10_t state;
    curand_init(s.seed, kOffsetSubsequence, s.draw * kDrawWindow, &state);
    wk.u0 = static_cast<double>(1.0f - curand_uniform(&state));  // (0, 1] -> [0, 1)
  }
}

// 3. Normalise, per-block moment sums, prefix sums of w for resampling sessions.
__global__ void __launch_bounds__(kBlockThreads)
    NormaliseKernel(const SessionStep* __restrict__ steps, const int* __restrict__ block_request,
                    const SessionWork* __restrict__ work) {
  __shared__ float rows[kMomentSums * kBlockThreads];
  __shared__ float total[kMomentSums];
  __shared__ BlockScan::TempStorage scan_storage;
  const int r = block_request[blockIdx.x];
  const SessionStep& s = steps[r];
  const SessionWork& wk = work[r];
  const int local_block = static_cast<int>(blockIdx.x) - s.first_block;
  const int i = local_block * kBlockThreads + static_cast<int>(threadIdx.x);
  const bool valid = i < s.slot.particles;
  float w = 0.0f;
  if (valid) {
    if (s.do_update) {
      const float lw = s.slot.logw[i];
      w = expf(lw - wk.max_logw) * wk.inv_sum;
      s.slot.w[i] = w;
      s.slot.logw[i] = lw - wk.log_norm;
    } else {
      w = s.slot.w[i];
    }
  }
  float shift[6], x[6];
#pragma unroll
  for (int c = 0; c < 6; ++c) {
    shift[c] = s.slot.state[c][0];
    x[c] = valid ? s.slot.state[c][i] : shift[c];
  }
  float terms[kMomentSums];
  MomentTerms(x, shift, w, terms);
  BlockSumRows(terms, rows, total);
  BlockPartial& part = s.slot.partials[local_block];
  if (threadIdx.x < kMomentSums) part.moments[threadIdx.x] = total[threadIdx.x];
  if (wk.resample) {  // uniform over the block
    double inclusive = 0.0, block_total = 0.0;
    BlockScan(scan_storage).InclusiveSum(static_cast<double>(w), inclusive, block_total);
    if (valid) s.slot.cumsum[i] = inclusive;
    if (threadIdx.x == 0) part.w_total = block_total;
  }
}

// 4. Per session: mean and covariance; for resampling sessions the block offsets of the
// prefix sums and the Liu-West kernel.
__global__ void __launch_bounds__(kBlockThreads)
    SessionMomentsKernel(const SessionStep* __restrict__ steps, SessionWork* __restrict__ work,
                         StepOutput* __restrict__ out) {
  __shared__ double dscratch[kWarps * kMomentSums];
  __shared__ double dtotal[kMomentSums];
  __shared__ BlockScan::TempStorage scan_storage;
  const SessionStep& s = steps[blockIdx.x];
  SessionWork& wk = work[blockIdx.x];
  StepOutput& o = out[blockIdx.x];
  BlockPartial* parts = s.slot.partials;
  const int blocks = s.slot.blocks;
  double acc[kMomentSums];
#pragma unroll
  for (int k = 0; k < kMomentSums; ++k) acc[k] = 0.0;
  for (int b = threadIdx.x; b < blocks; b += kBlockThreads) {
#pragma unroll
    for (int k = 0; k < kMomentSums; ++k) acc[k] += parts[b].moments[k];
  }
  BlockReduceShuffle(acc, SumOp(), dscratch, dtotal);
  const bool resample = wk.resample != 0;
  if (threadIdx.x == 0) {
    float shift[6];
    for (int c = 0; c < 6; ++c) shift[c] = s.slot.state[c][0];
    double mean[6], cov[36];
    FinishMoments(dtotal, shift, mean, cov);
    for (int c = 0; c < 6; ++c) o.mean[c] = mean[c];
    for (int k = 0; k < 36; ++k) o.cov[k] = cov[k];
    o.cholesky_fallback = 0;
    if (resample && s.kernel) {
      double l[36];
      o.cholesky_fallback = CholeskyLower6(cov, l) ? 0 : 1;
      const double a = s.kernel_a, h = s.kernel_h;
      wk.lw_a = static_cast<float>(a);
      int k = 0;
      for (int row = 0; row < 6; ++row) {
        wk.lw_shift[row] = static_cast<float>((1.0 - a) * mean[row]);
        for (int c = 0; c <= row; ++c) wk.lw_root[k++] = static_cast<float>(h * l[row * 6 + c]);
      }
    }
  }
  if (!resample) return;  // uniform over the block
  // Exclusive scan of the block totals: each thread a contiguous run of blocks.
  const int chunk = (blocks + kBlockThreads - 1) / kBlockThreads;
  const int begin = min(blocks, static_cast<int>(threadIdx.x) * chunk);
  const int end = min(blocks, begin + chunk);
  double run = 0.0;
  for (int b = begin; b < end; ++b) run += parts[b].w_total;
  double before = 0.0;
  BlockScan(scan_storage).ExclusiveSum(run, before);
  for (int b = begin; b < end; ++b) {
    parts[b].w_offset = before;
    before += parts[b].w_total;
  }
}

// 5. Systematic resampling by binary search, Liu-West move, into the other buffer.
__global__ void __launch_bounds__(kBlockThreads)
    ResampleKernel(const SessionStep* __restrict__ steps, const int* __restrict__ block_request,
                   const SessionWork* __restrict__ work) {
  const int r = block_request[blockIdx.x];
  const SessionWork& wk = work[r];
  if (!wk.resample) return;
  const SessionStep& s = steps[r];
  const int n = s.slot.particles;
  const int i = (static_cast<int>(blockIdx.x) - s.first_block) * kBlockThreads + static_cast<int>(threadIdx.x);
  if (i >= n) return;
  const int parent = SystematicParent(Cumulative{s.slot.cumsum, s.slot.partials}, n, wk.u0, i);
  float x[6], y[6];
#pragma unroll
  for (int c = 0; c < 6; ++c) x[c] = s.slot.state[c][parent];
  if (s.kernel) {
    curandStatePhilox4_32_10_t state;
    curand_init(s.seed, static_cast<unsigned long long>(i), s.draw * kDrawWindow + 4, &state);
    const float4 z0 = curand_normal4(&state), z1 = curand_normal4(&state);
    const float z[6] = {z0.x, z0.y, z0.z, z0.w, z1.x, z1.y};
    LiuWestMove(x, wk.lw_a, wk.lw_shift, wk.lw_root, z, y);
  } else {
#pragma unroll
    for (int c = 0; c < 6; ++c) y[c] = x[c];
  }
#pragma unroll
  for (int c = 0; c < 6; ++c) s.slot.next[c][i] = y[c];
  s.slot.logw[i] = -logf(static_cast<float>(n));
  s.slot.w[i] = 1.0f / static_cast<float>(n);
}

// Particle i of a slot: one Philox window's first values, the shared maths, equal weights.
__device__ __forceinline__ void InitialiseGaussianParticle(const SlotView& slot, const GaussianInit& init, int i) {
  curandStatePhilox4_32_10_t state;
  curand_init(init.seed, static_cast<unsigned long long>(i), init.draw * kDrawWindow, &state);
  const float4 a = curand_normal4(&state), b = curand_normal4(&state);
  const float z[6] = {a.x, a.y, a.z, a.w, b.x, b.y};
  float x[6];
  GaussianParticle(init.mean, init.root, z, x);
#pragma unroll
  for (int r = 0; r < 6; ++r) slot.state[r][i] = x[r];
  slot.logw[i] = -logf(static_cast<float>(slot.particles));
  slot.w[i] = 1.0f / static_cast<float>(slot.particles);
}

__device__ __forceinline__ void InitialiseRegionParticle(const SlotView& slot, const RegionInit& init, int i) {
  curandStatePhilox4_32_10_t state;
  curand_init(init.seed, static_cast<unsigned long long>(i), init.draw * kDrawWindow, &state);
  const float4 u = curand_uniform4(&state);  // (0, 1]
  const float4 v = curand_normal4(&state);
  const float uu[3] = {u.x, u.y, u.z}, vv[3] = {v.x, v.y, v.z};
  float x[6];
  RegionParticle(init.lo, init.span, init.speed_sigma, uu, vv, x);
#pragma unroll
  for (int r = 0; r < 6; ++r) slot.state[r][i] = x[r];
  slot.logw[i] = -logf(static_cast<float>(slot.particles));
  slot.w[i] = 1.0f / static_cast<float>(slot.particles);
}

__global__ void __launch_bounds__(kBlockThreads) InitialiseGaussianKernel(SlotView slot, GaussianInit init) {
  const int i = static_cast<int>(blockIdx.x) * kBlockThreads + static_cast<int>(threadIdx.x);
  if (i < slot.particles) InitialiseGaussianParticle(slot, init, i);
}

__global__ void __launch_bounds__(kBlockThreads) InitialiseRegionKernel(SlotView slot, RegionInit init) {
  const int i = static_cast<int>(blockIdx.x) * kBlockThreads + static_cast<int>(threadIdx.x);
  if (i < slot.particles) InitialiseRegionParticle(slot, init, i);
}

// Every block belongs to one slot (block_task), particle index from the slot's first block.
__global__ void __launch_bounds__(kBlockThreads)
    InitialiseBatchKernel(const InitTask* __restrict__ tasks, const int* __restrict__ block_task) {
  const InitTask& t = tasks[block_task[blockIdx.x]];
  const int i = (static_cast<int>(blockIdx.x) - t.first_block) * kBlockThreads + static_cast<int>(threadIdx.x);
  if (i >= t.slot.particles) return;
  if (t.kind == kInitGaussian) {
    InitialiseGaussianParticle(t.slot, t.gaussian, i);
  } else {
    InitialiseRegionParticle(t.slot, t.region, i);
  }
}

}  // namespace

Status LaunchStep(const StepLaunch& launch, cudaStream_t stream) {
  if (launch.requests <= 0 || launch.blocks <= 0) return Status::Ok();
  const dim3 grid(static_cast<unsigned>(launch.blocks)), sessions(static_cast<unsigned>(launch.requests));
  WeighKernel<<<grid, kBlockThreads, 0, stream>>>(launch.steps, launch.block_request, launch.gcc);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("WeighKernel");
  SessionWeightsKernel<<<sessions, kBlockThreads, 0, stream>>>(launch.steps, launch.work, launch.out);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("SessionWeightsKernel");
  NormaliseKernel<<<grid, kBlockThreads, 0, stream>>>(launch.steps, launch.block_request, launch.work);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("NormaliseKernel");
  SessionMomentsKernel<<<sessions, kBlockThreads, 0, stream>>>(launch.steps, launch.work, launch.out);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("SessionMomentsKernel");
  ResampleKernel<<<grid, kBlockThreads, 0, stream>>>(launch.steps, launch.block_request, launch.work);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("ResampleKernel");
  return Status::Ok();
}

Status LaunchInitialiseGaussian(const SlotView& slot, const GaussianInit& init, cudaStream_t stream) {
  if (slot.particles <= 0) return Status::Ok();
  InitialiseGaussianKernel<<<slot.blocks, kBlockThreads, 0, stream>>>(slot, init);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("InitialiseGaussianKernel");
  return Status::Ok();
}

Status LaunchInitialiseRegion(const SlotView& slot, const RegionInit& init, cudaStream_t stream) {
  if (slot.particles <= 0) return Status::Ok();
  InitialiseRegionKernel<<<slot.blocks, kBlockThreads, 0, stream>>>(slot, init);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("InitialiseRegionKernel");
  return Status::Ok();
}

Status LaunchInitialiseBatch(const InitLaunch& launch, cudaStream_t stream) {
  if (launch.blocks <= 0) return Status::Ok();
  InitialiseBatchKernel<<<launch.blocks, kBlockThreads, 0, stream>>>(launch.tasks, launch.block_task);
  LOCALIZER_LAUNCH_RETURN_IF_ERROR("InitialiseBatchKernel");
  return Status::Ok();
}

}  // namespace localizer::gpu::pf
