// ParticleSet's resampling (particle_set.h): systematic resampling and the Liu & West kernel
// move that follows it. Split from particle_set.cc, which holds sampling, prediction and
// weighing.
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <utility>
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include "engine/core/fast_math.h"
#include "engine/filters/lane_sums.h"
#include "engine/filters/particle_gather.h"
#include "engine/filters/particle_set.h"

namespace localizer::engine {

// A lower-triangular L with L L^T = covariance: Cholesky when the covariance is positive
// definite, else (a collapsed dimension) the QR-triangularised eigen square root.
Mat6 CovarianceRoot(const Mat6& covariance) {
  const Eigen::LLT<Mat6> llt(covariance);
  if (llt.info() == Eigen::Success) return llt.matrixL();
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(covariance);
  const Mat6 root = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  // root root^T = (R^T Q^T)(Q R) = R^T R for root^T = Q R, so L = R^T is a triangular root.
  const Mat6 r = Eigen::HouseholderQR<Mat6>(root.transpose()).matrixQR().triangularView<Eigen::Upper>();
  return r.transpose();
}

namespace {

// Two unit-variance kernel draws from one 32-bit hash of (key, counter): each the sum of
// two of its bytes, centred and scaled (a triangular kernel, |z| <= 2.44), at a fraction of
// the cost of an exact normal; the kernel's shape matters little (Epanechnikov's is the
// optimum). Draw k of particle m (k = 0 .. 5) is half (k % 2) of counter (k - k % 2) N + m.
inline void KernelDrawPair(uint32_t key, uint32_t counter, float* za, float* zb) {
  constexpr float kTwoBytesToUnitVariance = 1.0f / 104.5f;  // sqrt(2 * (256^2 - 1) / 12)
  const uint32_t bits = HashMix32(counter * 0x9e3779b9U + key);
  const uint32_t low = (bits & 0xffU) + ((bits >> 8) & 0xffU);
  const uint32_t high = ((bits >> 16) & 0xffU) + (bits >> 24);
  *za = (static_cast<float>(static_cast<int32_t>(low)) - 255.0f) * kTwoBytesToUnitVariance;
  *zb = (static_cast<float>(static_cast<int32_t>(high)) - 255.0f) * kTwoBytesToUnitVariance;
}

// index[m] <- max(index[0 .. m]) for values >= 0. The scalar loop is one max per slot in a
// chain; with AVX-512, 16 slots at a time: a prefix maximum within the vector in four shifted
// steps (zeros shifted in), then the maximum carried from the slots before.
void RunningMax(int* __restrict index, int n) {
  int m = 0;
  int running = 0;
#if defined(__AVX512F__)
  const __m512i zero = _mm512_setzero_si512();
  const __m512i last = _mm512_set1_epi32(15);
  __m512i carry = zero;
  for (; m + 16 <= n; m += 16) {
    __m512i v = _mm512_loadu_si512(index + m);
    v = _mm512_max_epi32(v, _mm512_alignr_epi32(v, zero, 15));  // lane k also sees lane k - 1
    v = _mm512_max_epi32(v, _mm512_alignr_epi32(v, zero, 14));  // ... k - 2 .. k - 3
    v = _mm512_max_epi32(v, _mm512_alignr_epi32(v, zero, 12));  // ... k - 4 .. k - 7
    v = _mm512_max_epi32(v, _mm512_alignr_epi32(v, zero, 8));   // ... k - 8 .. k - 15
    v = _mm512_max_epi32(v, carry);
    _mm512_storeu_si512(index + m, v);
    carry = _mm512_permutexvar_epi32(last, v);
  }
  if (m > 0) running = index[m - 1];
#endif
  for (; m < n; ++m) {
    running = std::max(running, index[m]);
    index[m] = running;
  }
}

}  // namespace

#if defined(__AVX512F__)
namespace {

// Systematic resampling's indices advance about one particle per slot, so 16 slots' parents
// nearly always lie within 32 consecutive particles from index[0]: two loads and a permute.
inline bool ParentsNear(const int* index, int n) { return index[15] - index[0] < 32 && index[0] + 32 <= n; }

// The 16 values column[index[k]]: near (ParentsNear), from the two loads at index[0]
// permuted by offset = index - index[0]; otherwise a 16-way gather.
inline __m512 GatherColumn16(const float* column, const int* index, bool near, __m512i offset, __m512i slots) {
  if (!near) return _mm512_i32gather_ps(slots, column, 4);
  const float* src = column + index[0];
  return _mm512_permutex2var_ps(_mm512_loadu_ps(src), offset, _mm512_loadu_ps(src + 16));
}

}  // namespace

void GatherParents16(const std::array<float*, 6>& from, const int* index, int n, float (*parent)[16]) {
  const __m512i slots = _mm512_loadu_si512(index);
  const __m512i offset = _mm512_sub_epi32(slots, _mm512_set1_epi32(index[0]));
  const bool near = ParentsNear(index, n);
  for (int r = 0; r < 6; ++r) _mm512_store_ps(parent[r], GatherColumn16(from[r], index, near, offset, slots));
}
#endif

void GatherSorted(const float* __restrict src, const int* __restrict index, int n, float* __restrict dst) {
  int m = 0;
#if defined(__AVX512F__)
  for (; m + 16 <= n; m += 16) {
    const __m512i slots = _mm512_loadu_si512(index + m);
    const __m512i offset = _mm512_sub_epi32(slots, _mm512_set1_epi32(index[m]));
    _mm512_storeu_ps(dst + m, GatherColumn16(src, index + m, ParentsNear(index + m, n), offset, slots));
  }
#endif
  for (; m < n; ++m) dst[m] = src[index[m]];
}

void ParticleSet::ResampleSystematic(double kernel_scale) {
  if (labels_ > 1) {
    ResampleModes(kernel_scale);
    return;
  }
  SystematicIndices();
  CarryLevels();
  const int n = n_;
  const int* __restrict index = index_.data();
  const std::array<float*, 6> from = cur_.Pointers(), to = next_.Pointers();
  if (kernel_scale <= 0.0) {
    for (int r = 0; r < 6; ++r) {
      const float* __restrict src = from[r];
      float* __restrict dst = to[r];
#pragma omp simd
      for (int m = 0; m < n; ++m) dst[m] = src[index[m]];
    }
    std::swap(cur_, next_);
    SetEqualWeights();
    return;
  }
  // Copy and kernel move in one pass per column:
  //   x'_m = a x_index[m] + (1 - a) mean + h L z_m
  const TrackState moments = MeanAndCovariance();
  const double h = KernelBandwidth(kernel_scale, n);
  const double a = KernelShrinkage(h);
  const Eigen::Matrix<float, 6, 6> l = (h * CovarianceRoot(moments.covariance)).cast<float>();
  Vec6 centre = moments.mean;
  centre.head<3>() -= origin_m_;
  const Eigen::Matrix<float, 6, 1> shift = ((1.0 - a) * centre).cast<float>();
  const float fa = static_cast<float>(a);
  // One pass over the slots: each reads its parent's six values once (one index load, six
  // gathers), draws its six kernel values from three hashes (the draws DrawKernelNoise
  // would store, without the 6 stores and 21 loads per particle) and writes six values.
  // The root is lower triangular: row r reads z_0 .. z_r only (21 terms, not 36).
  float root[21];
  for (int r = 0, t = 0; r < 6; ++r) {
    for (int k = 0; k <= r; ++k) root[t++] = l(r, k);
  }
  const float* __restrict l0 = root;
  const float* __restrict l1 = root + 1;
  const float* __restrict l2 = root + 3;
  const float* __restrict l3 = root + 6;
  const float* __restrict l4 = root + 10;
  const float* __restrict l5 = root + 15;
  const float s0 = shift(0), s1 = shift(1), s2 = shift(2), s3 = shift(3), s4 = shift(4), s5 = shift(5);
  const float* __restrict x0 = from[0];
  const float* __restrict x1 = from[1];
  const float* __restrict x2 = from[2];
  const float* __restrict x3 = from[3];
  const float* __restrict x4 = from[4];
  const float* __restrict x5 = from[5];
  float* __restrict y0 = to[0];
  float* __restrict y1 = to[1];
  float* __restrict y2 = to[2];
  float* __restrict y3 = to[3];
  float* __restrict y4 = to[4];
  float* __restrict y5 = to[5];
  const uint32_t key = NextKey();
  const uint32_t un = static_cast<uint32_t>(n);
  // Slot m's kernel move from its parent's six values p0 .. p5. Always inlined: called, the
  // loops below would not vectorise (GCC dropped the inlining after an unrelated header
  // change, and the step took 12.4 ns instead of 6.8).
  const auto move = [=](int m, float p0, float p1, float p2, float p3, float p4, float p5)
      __attribute__((always_inline)) {
    float z0, z1, z2, z3, z4, z5;  // scalars, not an array: an array costs the loop its vector form
    const uint32_t c = static_cast<uint32_t>(m);
    KernelDrawPair(key, c, &z0, &z1);
    KernelDrawPair(key, 2u * un + c, &z2, &z3);
    KernelDrawPair(key, 4u * un + c, &z4, &z5);
    const auto draw = [=](int k) { return k == 0 ? z0 : k == 1 ? z1 : k == 2 ? z2 : k == 3 ? z3 : k == 4 ? z4 : z5; };
    y0[m] = LiuWestRow(fa, p0, s0, l0, 0, draw);
    y1[m] = LiuWestRow(fa, p1, s1, l1, 1, draw);
    y2[m] = LiuWestRow(fa, p2, s2, l2, 2, draw);
    y3[m] = LiuWestRow(fa, p3, s3, l3, 3, draw);
    y4[m] = LiuWestRow(fa, p4, s4, l4, 4, draw);
    y5[m] = LiuWestRow(fa, p5, s5, l5, 5, draw);
  };
  int first = 0;
#if defined(__AVX512F__)
  // Whole blocks of 16 slots: their parents gathered by GatherParents16 (mostly two loads and
  // a permute per column instead of a 16-way gather), then moved as the scalar loop below.
  alignas(64) float parent[6][16];
  for (; first + 16 <= n; first += 16) {
    GatherParents16(from, index + first, n, parent);
#pragma omp simd simdlen(16)
    for (int k = 0; k < 16; ++k) {
      move(first + k, parent[0][k], parent[1][k], parent[2][k], parent[3][k], parent[4][k], parent[5][k]);
    }
  }
#endif
#pragma omp simd
  for (int m = first; m < n; ++m) {
    const int j = index[m];
    move(m, x0[j], x1[j], x2[j], x3[j], x4[j], x5[j]);
  }
  std::swap(cur_, next_);
  SetEqualWeights();
  // Shrinkage and kernel keep the mean and covariance (Liu & West): the moments computed
  // before resampling stay the estimate.
  moments_ = moments;
  moments_valid_ = true;
}

void ParticleSet::SystematicIndices() {
  // Branch-free systematic resampling: particle i owns the pointers (u0 + m) / N that fall
  // in (C_{i-1}, C_i], i.e. slots [k_{i-1}, k_i) with k_i = ceil(N C_i - u0). Each particle
  // marks the first slot of its range (the last writer of a slot is the one whose range is
  // non-empty) and a running max spreads the marks over the ranges.
  const float u0 = UniformFromCounter(NextKey(), 0);
  const int n = n_;  // a local bound: stores through int* could alias the member
  const float* __restrict w = w_.data();
  int* __restrict index = index_.data();
  int* __restrict first_slot = first_slot_.data();
  // Prefix sums in kChains interleaved runs so the additions do not wait on each other: run
  // k covers [k * len, (k + 1) * len) and starts from the sum of the runs before it.
  constexpr int kChains = 8;
  const int len = n / kChains;
  double acc[kChains];
  double before = 0.0;
  for (int k = 0; k < kChains; ++k) {
    acc[k] = before;
    double run[1];
    LaneSums<double, 1>(
        k * len, (k + 1) * len, {0.0}, [&](int i, int lane, double(*sum)[kSumLanes<double>]) { sum[0][lane] += w[i]; },
        run);
    before += run[0];
  }
  const double scale = n;
  for (int j = 0; j < len; ++j) {
    for (int k = 0; k < kChains; ++k) {
      const int i = k * len + j;
      acc[k] += w[i];
      first_slot[i] = static_cast<int>(std::ceil(acc[k] * scale - u0));
    }
  }
  for (int i = kChains * len; i < n; ++i) {  // the remainder, after the last run
    before += w[i];
    first_slot[i] = static_cast<int>(std::ceil(before * scale - u0));
  }
  // first_slot is non-decreasing (cumulative weights are) and >= 0 (u0 < 1); the last
  // particle starting at slot s marks it, which is the one whose range is non-empty.
  std::fill(index, index + n, 0);
  for (int i = 1; i < n; ++i) {
    const int start = first_slot[i - 1];
    if (start < n) index[start] = i;
  }
  RunningMax(index, n);
}

void ParticleSet::DrawKernelNoise() {
  // The same draws as ResampleSystematic's fused pass (KernelDrawPair), stored per column.
  const uint32_t key = NextKey();
  const int n = n_;
  for (int k = 0; k < 6; k += 2) {
    float* __restrict za = noise_[k].data();
    float* __restrict zb = noise_[k + 1].data();
    const uint32_t offset = static_cast<uint32_t>(k) * static_cast<uint32_t>(n);
#pragma omp simd
    for (int i = 0; i < n; ++i) KernelDrawPair(key, offset + static_cast<uint32_t>(i), &za[i], &zb[i]);
  }
}

}  // namespace localizer::engine
