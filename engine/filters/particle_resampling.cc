// ParticleSet's resampling (particle_set.h): systematic resampling and the Liu & West kernel
// move that follows it. Split from particle_set.cc, which holds sampling, prediction and
// weighing.
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <utility>

#include "engine/core/fast_math.h"
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

// dst[m] = a src[index[m]] + shift + sum_{k <= kRow} l_row[k * stride] z_k[m]: one state
// column resampled and moved by the kernel in one pass (particle_math.h LiuWestRow).
template <int kRow>
void MoveRow(int n, const int* __restrict index, const float* __restrict src, float* __restrict dst, float a,
             float shift, const float* l_row, Eigen::Index stride, const std::array<const float*, 6>& z) {
  float coeff[kRow + 1];
  for (int k = 0; k <= kRow; ++k) coeff[k] = l_row[k * stride];
#pragma omp simd
  for (int m = 0; m < n; ++m) {
    dst[m] = LiuWestRow(a, src[index[m]], shift, coeff, kRow, [&z, m](int k) { return z[k][m]; });
  }
}

}  // namespace

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
  DrawKernelNoise();
  const std::array<const float*, 6> z = {noise_[0].data(), noise_[1].data(), noise_[2].data(),
                                         noise_[3].data(), noise_[4].data(), noise_[5].data()};
  // The root is lower triangular: row r reads z_0 .. z_r only (21 terms, not 36).
  [&]<int... kRow>(std::integer_sequence<int, kRow...>) {
    (MoveRow<kRow>(n, index, from[kRow], to[kRow], fa, shift(kRow), l.row(kRow).data(), l.rows(), z), ...);
  }
  (std::make_integer_sequence<int, 6>{});
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
    double run = 0.0;
#pragma omp simd reduction(+ : run)
    for (int i = k * len; i < (k + 1) * len; ++i) run += w[i];
    before += run;
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
  int running = 0;
  for (int m = 0; m < n; ++m) {
    running = std::max(running, index[m]);
    index[m] = running;
  }
}

void ParticleSet::DrawKernelNoise() {
  // Each 32-bit hash gives two draws, each the sum of two of its bytes scaled to unit
  // variance: a triangular kernel, |z| <= 2.44, at a fraction of the cost of an exact
  // normal; the kernel's shape matters little (Epanechnikov's is the optimum).
  constexpr float kTwoBytesToUnitVariance = 1.0f / 104.5f;  // sqrt(2 * (256^2 - 1) / 12)
  const uint32_t key = NextKey();
  const int n = n_;
  for (int k = 0; k < 6; k += 2) {
    float* __restrict za = noise_[k].data();
    float* __restrict zb = noise_[k + 1].data();
    const uint32_t offset = static_cast<uint32_t>(k) * static_cast<uint32_t>(n);
#pragma omp simd
    for (int i = 0; i < n; ++i) {
      const uint32_t bits = HashMix32((offset + static_cast<uint32_t>(i)) * 0x9e3779b9U + key);
      const uint32_t low = (bits & 0xffU) + ((bits >> 8) & 0xffU);
      const uint32_t high = ((bits >> 16) & 0xffU) + (bits >> 24);
      za[i] = (static_cast<float>(static_cast<int32_t>(low)) - 255.0f) * kTwoBytesToUnitVariance;
      zb[i] = (static_cast<float>(static_cast<int32_t>(high)) - 255.0f) * kTwoBytesToUnitVariance;
    }
  }
}

}  // namespace localizer::engine
