// Launchers of the particle bank's kernels (pf_kernels.cu) and the plain structs they read
// and write. Host code (particle_bank.cc) fills the descriptors; nothing here needs nvcc.
//
// One Step is one launch sequence on one stream over R requests (sessions), whose particles
// are tiled by blocks of kBlockThreads; every block belongs to one session, so per-session
// results never depend on which other sessions share the launch:
//   1. WeighKernel (one thread per particle, every session): predict (Philox normals), then,
//      for sessions with a measurement, pair delays, log-likelihood, log-weight update; per
//      block: max log-weight m_b, sum of exp(logw - m_b) and of its square, and the prior
//      innovation sums sum w e, sum w e^2 (e in sigmas) per pair, in float.
//   2. SessionWeightsKernel (one block per session): log-sum-exp over the session's blocks in
//      double (S = sum_b s_b e^(m_b - M)), ESS = S^2 / Q, the resampling decision
//      (ESS < threshold N), the innovation moments; draws the resampling offset u0.
//   3. NormaliseKernel (every particle): w = e^(logw - M) / S, logw -= M + log S; per-block
//      weighted moment sums about particle 0 (float); for sessions that resample, the
//      block's inclusive prefix sums of w in double and its total.
//   4. SessionMomentsKernel (one block per session): moment sums over blocks in double ->
//      mean and covariance; for sessions that resample: block offsets of the prefix sums
//      (a block scan) and the Liu-West kernel (Cholesky of the covariance in double).
//   5. ResampleKernel (every particle of sessions that resample): each output slot finds
//      its parent by binary search of the prefix sums, moves by the kernel (Philox normals)
//      and is written to the slot's other state buffer; weights reset to 1/N.
// The decision to resample is made on the device (steps 2-5 read SessionWork), so the host
// waits once, for the StepOutput copy.
//
// Random numbers: curand Philox4_32_10 keyed by the session's seed, subsequence = particle
// index, offset = kDrawWindow * draw, draw a per-session counter the host advances once per
// Step that draws (and per initialisation). Within a window: values 0-3 the predict normals,
// 4-11 the kernel normals. The resampling offset uses subsequence kOffsetSubsequence.
#pragma once

#include <cuda_runtime_api.h>

#include <cstdint>

#include "engine/core/status.h"

namespace localizer::gpu::pf {

inline constexpr int kBlockThreads = 256;
inline constexpr int kMaxPairs = 15;                                  // at most 16 sensors
inline constexpr int kWeighedSums = 28;                               // = kMomentSums (pf_math.cuh)
inline constexpr unsigned long long kDrawWindow = 16;                 // 32-bit values per draw
inline constexpr unsigned long long kOffsetSubsequence = 1ull << 40;  // beyond any particle

// Per-block partial results (float within a block, as the CPU sums in float).
struct BlockPartial {
  float max_logw;               // m_b
  float sum_u;                  // sum exp(logw - m_b)
  float sum_u2;                 // sum exp(logw - m_b)^2
  float sum_e[kMaxPairs];       // sum w_prior e (e in sigmas)
  float sum_e2[kMaxPairs];      // sum w_prior e^2
  float moments[kWeighedSums];  // MomentTerms summed over the block
  double w_total;               // sum of the normalised weights (resampling sessions)
  double w_offset;              // sum of the w_total of the blocks before (idem)
};

// A slot's device arrays (one session's particles).
struct SlotView {
  float* state[6] = {};              // current columns x, y, z, vx, vy, vz (relative to the centroid)
  float* next[6] = {};               // the other buffer: resampling writes here, then the slot flips
  float* logw = nullptr;             // normalised log-weights
  float* w = nullptr;                // normalised weights
  double* cumsum = nullptr;          // scratch: within-block inclusive prefix sums of w
  BlockPartial* partials = nullptr;  // one per block
  int particles = 0;
  int blocks = 0;  // ceil(particles / kBlockThreads)
};

// One pair's inputs to the likelihood.
struct PairParams {
  float sensor[3];     // sensor position relative to the centroid (m)
  float delay_s;       // measured TDOA d
  float half_delay_s;  // d / 2
  float inv_sigma;     // 1 / TDOA noise std (1/s)
  int used;            // 0: the pair is left out
  int gcc_offset;      // >= 0: GCC likelihood, fine window at gcc + gcc_offset; -1: peak
  float lag_scale;     // fs * upsampling
  float lag0;          // first_lag_samples * upsampling
  float last_lag;      // fine length - 3 - 1e-3
  float gcc_gain;      // GccGain of the fine window
  float blur_var_s2;   // > 0: motion blur, the share of V this pair takes (engine particle_set.h)
};

// One request of a Step, as the kernels read it.
struct SessionStep {
  SlotView slot;
  int first_block = 0;  // this session's first block in the step's grid
  int pairs = 0;        // pair count of the array (<= kMaxPairs)
  int do_predict = 0;
  int do_update = 0;
  float dt = 0, a_to_p = 0, a_to_v = 0;      // predict (pf_math.cuh PredictParticle)
  float manoeuvre_z = -1e30f;                // a particle manoeuvres when its 4th normal < this
  float quiet_gain = 1, manoeuvre_gain = 1;  // its acceleration normals' gain (ManoeuvreGainsFor)
  float reference[3] = {};                   // reference sensor relative to the centroid
  float inv_c = 0;                           // 1 / sound speed (s/m)
  float inv_dof = 0, half_dof_plus_1 = 0;    // Student-t
  double resample_below = 0;                 // resample when ESS < this (threshold * N)
  int kernel = 0;                            // 1: Liu-West move after resampling
  double kernel_h = 0, kernel_a = 0;         // bandwidth h and shrinkage a = sqrt(1 - h^2)
  double prior_ess = 0;                      // reported unchanged when there is no update
  unsigned long long seed = 0;
  unsigned long long draw = 0;  // the Philox window of this step
  PairParams pair[kMaxPairs] = {};
};

// Per-request scalars passed between kernels (device only).
struct SessionWork {
  float max_logw;     // M
  float inv_sum;      // 1 / S
  float log_norm;     // M + log S
  int resample;       // this session resamples in this step
  double u0;          // systematic offset in [0, 1)
  float lw_a;         // Liu-West shrinkage
  float lw_shift[6];  // (1 - a) mean (relative to the centroid)
  float lw_root[21];  // h chol(cov), packed lower triangular
};

// Per-request results copied back (relative to the centroid; the host adds it).
struct StepOutput {
  double mean[6];
  double cov[36];
  double ess;
  double sum_e[kMaxPairs];  // sum w_prior e over the session (e in sigmas)
  double sum_e2[kMaxPairs];
  int resampled;
  int cholesky_fallback;  // the covariance was not positive definite (see CholeskyLower6)
};

struct StepLaunch {
  const SessionStep* steps = nullptr;  // device, one per request
  const int* block_request = nullptr;  // device, one per grid block: its request
  const float* gcc = nullptr;          // device: the step's fine GCC windows
  SessionWork* work = nullptr;         // device, one per request
  StepOutput* out = nullptr;           // device, one per request
  int requests = 0;
  int blocks = 0;
};

// Enqueues kernels 1-5 on `stream`; errors of the launches (not of their execution) here.
Status LaunchStep(const StepLaunch& launch, cudaStream_t stream);

// x = mean + root z, z ~ N(0, I6) (Philox window `draw`); weights 1/N.
struct GaussianInit {
  float mean[6];   // relative to the centroid
  float root[36];  // row-major
  unsigned long long seed, draw;
};
Status LaunchInitialiseGaussian(const SlotView& slot, const GaussianInit& init, cudaStream_t stream);

// Position uniform in [lo, lo + span], velocity ~ N(0, speed_sigma^2 I3); weights 1/N.
struct RegionInit {
  float lo[3];  // relative to the centroid
  float span[3];
  float speed_sigma;
  unsigned long long seed, draw;
};
Status LaunchInitialiseRegion(const SlotView& slot, const RegionInit& init, cudaStream_t stream);

// Batched (re)initialisation: many slots, each by its own kind and parameters, in ONE launch
// whose grid tiles every slot's particles by blocks (as a Step's does); a slot's particles
// get exactly what LaunchInitialiseGaussian / LaunchInitialiseRegion give them alone (the
// same per-particle functions, pf_math.cuh, and the same Philox keys). init_builder.h plans it.
enum InitKind : int32_t { kInitGaussian = 0, kInitRegion = 1 };
struct InitTask {
  SlotView slot;
  int32_t kind = kInitGaussian;
  int32_t first_block = 0;  // the slot's first block in the launch's grid
  GaussianInit gaussian{};  // read when kind == kInitGaussian
  RegionInit region{};      // read when kind == kInitRegion
};
struct InitLaunch {
  const InitTask* tasks = nullptr;  // device, one per slot
  const int* block_task = nullptr;  // device, one per grid block: its task
  int blocks = 0;
};
Status LaunchInitialiseBatch(const InitLaunch& launch, cudaStream_t stream);

}  // namespace localizer::gpu::pf
