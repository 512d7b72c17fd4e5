// The GPU particle filter's per-particle maths (gpu/filters/pf_math.cuh), run on the host:
// each function against the CPU engine's formula (engine/filters/particle_set.cc, copied
// here as the reference where the engine keeps it inside a loop) and against physics.
// Compiled by nvcc, so the functions are the very __host__ __device__ code the kernels use.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "gpu/filters/pf_math.cuh"

namespace localizer::gpu::pf {
namespace {

float Uniform(std::mt19937& rng, float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); }

void RandomState(std::mt19937& rng, float s[6]) {
  for (int k = 0; k < 3; ++k) s[k] = Uniform(rng, -30.0f, 30.0f);
  for (int k = 3; k < 6; ++k) s[k] = Uniform(rng, -5.0f, 5.0f);
}

// The initialisation kernels' per-particle maths (one slot or batched): mean + root z, in
// float, summed in k order, against the same sum in double; and a region's box.
TEST(PfMath, GaussianParticleIsMeanPlusRootTimesZ) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    float mean[6], root[36], z[6], x[6];
    for (float& m : mean) m = Uniform(rng, -50.0f, 50.0f);
    for (float& r : root) r = Uniform(rng, -2.0f, 2.0f);
    for (float& v : z) v = Uniform(rng, -4.0f, 4.0f);
    GaussianParticle(mean, root, z, x);
    for (int r = 0; r < 6; ++r) {
      double exact = mean[r];
      for (int k = 0; k < 6; ++k) exact += static_cast<double>(root[r * 6 + k]) * z[k];
      EXPECT_NEAR(x[r], exact, 1e-5 * (std::abs(mean[r]) + 50.0)) << r;
    }
  }
  const float mean[6] = {1, 2, 3, 4, 5, 6}, zero_root[36] = {}, z[6] = {9, 9, 9, 9, 9, 9};
  float x[6];
  GaussianParticle(mean, zero_root, z, x);
  for (int r = 0; r < 6; ++r) EXPECT_EQ(x[r], mean[r]);  // a point belief is exact
}

TEST(PfMath, RegionParticleSpansTheBoxAndScalesTheVelocity) {
  const float lo[3] = {-2.0f, 10.0f, 0.5f}, span[3] = {4.0f, 0.0f, 1.5f};
  const float top[3] = {1.0f, 1.0f, 1.0f}, v[3] = {1.0f, -2.0f, 0.5f};
  float x[6];
  RegionParticle(lo, span, 0.25f, top, v, x);  // u = 1: the box's far corner
  EXPECT_EQ(x[0], 2.0f);
  EXPECT_EQ(x[1], 10.0f);
  EXPECT_EQ(x[2], 2.0f);
  EXPECT_EQ(x[3], 0.25f);
  EXPECT_EQ(x[4], -0.5f);
  EXPECT_EQ(x[5], 0.125f);
  const float tiny[3] = {1e-7f, 1e-7f, 1e-7f};
  RegionParticle(lo, span, 0.0f, tiny, v, x);  // u just above 0: at the near corner, at rest
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(x[a], lo[a], 1e-6f);
    EXPECT_EQ(x[3 + a], 0.0f);
  }
}

TEST(PfMath, PredictIsTheCpuStep) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 1000; ++trial) {
    float s[6];
    RandomState(rng, s);
    const double dt_s = Uniform(rng, 0.0f, 0.5f), accel = Uniform(rng, 0.0f, 3.0f);
    const float dt = static_cast<float>(dt_s);
    const float a_to_v = static_cast<float>(accel * dt_s), a_to_p = static_cast<float>(0.5 * accel * dt_s * dt_s);
    const float ax = Uniform(rng, -3, 3), ay = Uniform(rng, -3, 3), az = Uniform(rng, -3, 3);
    // ParticleSet::Predict's loop body.
    float x = s[0], y = s[1], z = s[2], vx = s[3], vy = s[4], vz = s[5];
    x += vx * dt + a_to_p * ax;
    y += vy * dt + a_to_p * ay;
    z += vz * dt + a_to_p * az;
    vx += a_to_v * ax;
    vy += a_to_v * ay;
    vz += a_to_v * az;
    PredictParticle(s, dt, a_to_p, a_to_v, ax, ay, az);
    EXPECT_EQ(s[0], x);
    EXPECT_EQ(s[1], y);
    EXPECT_EQ(s[2], z);
    EXPECT_EQ(s[3], vx);
    EXPECT_EQ(s[4], vy);
    EXPECT_EQ(s[5], vz);
  }
}

TEST(PfMath, PairDelayIsTheCpuFormula) {
  std::mt19937 rng(2);
  const float inv_c = 1.0f / 1500.0f;
  for (int trial = 0; trial < 1000; ++trial) {
    float s[6], ref[3], sensor[3];
    RandomState(rng, s);
    for (int k = 0; k < 3; ++k) {
      ref[k] = Uniform(rng, -1, 1);
      sensor[k] = Uniform(rng, -1, 1);
    }
    const float d = Uniform(rng, -1e-3f, 1e-3f), half_d = 0.5f * d;
    // ParticleSet::Weigh: r_ref, vr_ref, then per pair r, vr, h.
    float dx = s[0] - ref[0], dy = s[1] - ref[1], dz = s[2] - ref[2];
    const float r_ref = std::sqrt(dx * dx + dy * dy + dz * dz) + 1e-6f;
    const float vr_ref = (dx * s[3] + dy * s[4] + dz * s[5]) / r_ref;
    dx = s[0] - sensor[0], dy = s[1] - sensor[1], dz = s[2] - sensor[2];
    const float r = std::sqrt(dx * dx + dy * dy + dz * dz) + 1e-6f;
    const float vr = (dx * s[3] + dy * s[4] + dz * s[5]) / r;
    const float h_cpu = (r - r_ref) * inv_c - half_d * (vr - vr_ref) * inv_c;
    const RangeRate rr = RangeAndRate(s, ref[0], ref[1], ref[2]);
    const RangeRate rk = RangeAndRate(s, sensor[0], sensor[1], sensor[2]);
    EXPECT_EQ(rr.r, r_ref);
    EXPECT_EQ(rr.vr, vr_ref);
    EXPECT_EQ(PairDelay(rk, rr, half_d, inv_c), h_cpu);
  }
}

// Physics: h' is the TDOA of the source where it was d/2 earlier, to first order in v d: in
// air, 3.5 m away at 13 m/s, the motion moves the TDOA by ~3e-7 s, and h' follows it.
TEST(PfMath, PairDelayIsTheTdoaAtTheDescribedInstant) {
  const double c = 343.0, ref[3] = {0.5, 0.5, 0.5}, sensor[3] = {-0.5, -0.5, 0.5};
  const double p[3] = {3.0, -2.0, 1.5}, v[3] = {-10.0, 8.0, 4.0};
  const auto tdoa = [&](const double q[3]) {
    double rk = 0, rr = 0;
    for (int a = 0; a < 3; ++a) {
      rk += (q[a] - sensor[a]) * (q[a] - sensor[a]);
      rr += (q[a] - ref[a]) * (q[a] - ref[a]);
    }
    return (std::sqrt(rk) - std::sqrt(rr)) / c;
  };
  double d = tdoa(p), earlier[3];
  for (int it = 0; it < 5; ++it) {  // the delay the pair measures: at p - v d / 2
    for (int a = 0; a < 3; ++a) earlier[a] = p[a] - v[a] * d / 2;
    d = tdoa(earlier);
  }
  float s[6];
  for (int a = 0; a < 3; ++a) {
    s[a] = static_cast<float>(p[a]);
    s[3 + a] = static_cast<float>(v[a]);
  }
  const float h = PairDelay(RangeAndRate(s, -0.5f, -0.5f, 0.5f), RangeAndRate(s, 0.5f, 0.5f, 0.5f),
                            static_cast<float>(d / 2), static_cast<float>(1.0 / c));
  const double motion = std::abs(d - tdoa(p));
  EXPECT_GT(motion, 2e-7);
  EXPECT_LT(std::abs(h - d), 0.05 * motion) << "h " << h << " d " << d << " static " << tdoa(p);
}

TEST(PfMath, StudentTIsTheCpuLogLikelihood) {
  const double dof = 4.0;
  const float inv_dof = static_cast<float>(1.0 / dof), half = static_cast<float>(0.5 * (dof + 1.0));
  for (float e = -50.0f; e <= 50.0f; e += 0.37f) {
    const double want = -0.5 * (dof + 1.0) * std::log(1.0 + static_cast<double>(e) * e / dof);
    EXPECT_NEAR(StudentTLogLikelihood(e, inv_dof, half), want, 1e-6 * (1.0 + std::abs(want))) << e;
  }
  EXPECT_EQ(StudentTLogLikelihood(0.0f, inv_dof, half), 0.0f);
}

TEST(PfMath, CatmullRomIsTheCpuRead) {
  std::mt19937 rng(3);
  std::vector<float> g(401);
  for (float& v : g) v = Uniform(rng, -0.2f, 1.0f);
  const float first = 1.0f, last = static_cast<float>(g.size() - 3) - 1e-3f;
  for (int trial = 0; trial < 2000; ++trial) {
    const float lag_in = Uniform(rng, -20.0f, 420.0f);
    // ParticleSet::Weigh's GCC loop body.
    float lag = lag_in < first ? first : (lag_in > last ? last : lag_in);
    const int i0 = static_cast<int>(lag);
    const float t = lag - static_cast<float>(i0);
    const float gm = g[i0 - 1], g0 = g[i0], g1 = g[i0 + 1], g2 = g[i0 + 2];
    const float want =
        g0 + 0.5f * t * ((g1 - gm) + t * ((2.0f * gm - 5.0f * g0 + 4.0f * g1 - g2) + t * (3.0f * (g0 - g1) + g2 - gm)));
    EXPECT_EQ(engine::CatmullRomRead(g.data(), lag_in, last), want) << lag_in;
  }
  for (int k = 1; k < 398; ++k) EXPECT_EQ(engine::CatmullRomRead(g.data(), static_cast<float>(k), last), g[k]);
  EXPECT_EQ(engine::CatmullRomRead(g.data(), NAN, last), g[1]);  // a NaN delay reads inside the window
  EXPECT_FLOAT_EQ(engine::GccFineLag(1e-3f, 8 * 11025.0f, -8 * 40.0f), 1e-3f * 8 * 11025.0f + 8 * 40.0f);
}

// Reads C_j for SystematicParent (a __host__ __device__ callable, as on the device).
struct Cumulative {
  const double* c;
  LOCALIZER_HOST_DEVICE double operator()(int j) const { return c[j]; }
};

// ParticleSet::SystematicIndices' marking and running max, fed the same cumulative weights.
std::vector<int> CpuSystematic(const std::vector<double>& cum, float u0) {
  const int n = static_cast<int>(cum.size());
  std::vector<int> first_slot(n), index(n, 0);
  for (int i = 0; i < n; ++i) first_slot[i] = static_cast<int>(std::ceil(cum[i] * n - u0));
  for (int i = 1; i < n; ++i) {
    const int start = first_slot[i - 1];
    if (start < n) index[start] = i;
  }
  int running = 0;
  for (int m = 0; m < n; ++m) {
    running = std::max(running, index[m]);
    index[m] = running;
  }
  return index;
}

void ExpectSameParents(const std::vector<float>& weights, float u0) {
  std::vector<double> cum(weights.size());
  double acc = 0.0;
  for (size_t i = 0; i < weights.size(); ++i) cum[i] = acc += weights[i];
  const std::vector<int> want = CpuSystematic(cum, u0);
  const Cumulative read{cum.data()};
  const int n = static_cast<int>(weights.size());
  for (int m = 0; m < n; ++m) {
    ASSERT_EQ(SystematicParent(read, n, u0, m), want[m]) << "slot " << m << " of " << n << ", u0 " << u0;
  }
}

std::vector<float> Normalised(std::vector<float> w) {
  float sum = 0.0f;
  for (float v : w) sum += v;
  for (float& v : w) v /= sum;
  return w;
}

TEST(PfMath, SystematicParentsMatchTheCpuForRandomWeights) {
  std::mt19937 rng(4);
  for (int n : {16, 17, 255, 256, 1000, 4096}) {
    for (int trial = 0; trial < 5; ++trial) {
      std::vector<float> w(n);
      for (float& v : w) v = std::exp(Uniform(rng, -8.0f, 0.0f));
      ExpectSameParents(Normalised(w), Uniform(rng, 0.0f, 1.0f));
    }
  }
}

TEST(PfMath, SystematicParentsMatchTheCpuWithZeroWeights) {
  std::mt19937 rng(5);
  for (int n : {16, 300, 4096}) {
    std::vector<float> w(n);
    for (float& v : w) v = Uniform(rng, 0.0f, 1.0f) < 0.7f ? 0.0f : Uniform(rng, 0.0f, 1.0f);
    w[0] = 0.0f;  // leading and trailing zeros
    w[n - 1] = 0.0f;
    w[n / 2] = 0.5f;  // at least one positive
    const std::vector<float> normalised = Normalised(w);
    for (float u0 : {0.0f, 0.25f, 0.999999f}) ExpectSameParents(normalised, u0);
  }
}

TEST(PfMath, SystematicParentsWithOneDominantWeight) {
  for (int n : {16, 1000}) {
    std::vector<float> w(n, 1e-30f);
    w[n / 3] = 1.0f;
    const std::vector<float> normalised = Normalised(w);
    ExpectSameParents(normalised, 0.5f);
    std::vector<double> cum(n);
    double acc = 0.0;
    for (int i = 0; i < n; ++i) cum[i] = acc += normalised[i];
    const Cumulative read{cum.data()};
    for (int m = 0; m < n; ++m) EXPECT_EQ(SystematicParent(read, n, 0.5, m), n / 3);
  }
}

TEST(PfMath, SystematicParentsWhenTheWeightsSumBelowOne) {
  // Rounding leaves the total a little under 1: the last slots go to the last particle.
  std::vector<float> w(100, 0.0099f);
  ExpectSameParents(w, 0.9f);
  std::vector<double> cum(100);
  double acc = 0.0;
  for (int i = 0; i < 100; ++i) cum[i] = acc += w[i];
  const Cumulative read{cum.data()};
  EXPECT_EQ(SystematicParent(read, 100, 0.9, 99), 99);
}

void RandomSpd(std::mt19937& rng, int rank, double a[36]) {
  double b[36] = {};
  for (int r = 0; r < 6; ++r) {
    for (int k = 0; k < rank; ++k) b[r * 6 + k] = std::normal_distribution<double>(0.0, 1.0)(rng) * (r < 3 ? 2.0 : 0.1);
  }
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      double v = 0.0;
      for (int k = 0; k < 6; ++k) v += b[r * 6 + k] * b[c * 6 + k];
      a[r * 6 + c] = v;
    }
  }
}

double MaxReconstructionError(const double a[36], const double l[36]) {
  double worst = 0.0;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      double v = 0.0;
      for (int k = 0; k < 6; ++k) v += l[r * 6 + k] * l[c * 6 + k];
      worst = std::max(worst, std::abs(v - a[r * 6 + c]));
    }
  }
  return worst;
}

double MaxDiagonal(const double a[36]) {
  double m = 0.0;
  for (int i = 0; i < 6; ++i) m = std::max(m, a[i * 7]);
  return m;
}

TEST(PfMath, CholeskyReconstructsRandomSpdMatrices) {
  std::mt19937 rng(6);
  for (int trial = 0; trial < 200; ++trial) {
    double a[36], l[36];
    RandomSpd(rng, 6, a);
    for (int i = 0; i < 6; ++i) a[i * 7] += 1e-3;
    ASSERT_TRUE(CholeskyLower6(a, l));
    for (int r = 0; r < 6; ++r) {
      EXPECT_GT(l[r * 7], 0.0);
      for (int c = r + 1; c < 6; ++c) EXPECT_EQ(l[r * 6 + c], 0.0);
    }
    EXPECT_LT(MaxReconstructionError(a, l), 1e-12 * MaxDiagonal(a));
  }
}

TEST(PfMath, CholeskyFallbackOnSingularMatricesIsFiniteAndReconstructs) {
  std::mt19937 rng(7);
  for (int rank = 0; rank < 6; ++rank) {
    for (int trial = 0; trial < 50; ++trial) {
      double a[36], l[36];
      RandomSpd(rng, rank, a);
      CholeskyLower6(a, l);  // may report definite when rounding leaves pivots above tolerance
      for (double v : l) ASSERT_TRUE(std::isfinite(v));
      EXPECT_LT(MaxReconstructionError(a, l), 1e-9 * std::max(1.0, MaxDiagonal(a))) << "rank " << rank;
    }
  }
  // A collapsed velocity (all particles cloned, no kernel yet): exact zero rows and columns.
  double a[36] = {}, l[36];
  for (int i = 0; i < 3; ++i) a[i * 7] = 0.25 * (i + 1);
  a[1] = a[6] = 0.1;
  EXPECT_FALSE(CholeskyLower6(a, l));
  EXPECT_LT(MaxReconstructionError(a, l), 1e-15);
  // Slightly indefinite by rounding.
  a[35] = -1e-18;
  EXPECT_FALSE(CholeskyLower6(a, l));
  for (double v : l) EXPECT_TRUE(std::isfinite(v));
  EXPECT_LT(MaxReconstructionError(a, l), 1e-15);
}

TEST(PfMath, CholeskyOfZeroAndNonFiniteIsZero) {
  double a[36] = {}, l[36];
  EXPECT_FALSE(CholeskyLower6(a, l));
  for (double v : l) EXPECT_EQ(v, 0.0);
  a[7] = NAN;
  EXPECT_FALSE(CholeskyLower6(a, l));
  for (double v : l) EXPECT_EQ(v, 0.0);
}

TEST(PfMath, KernelBandwidthIsSilvermansAsTheCpu) {
  for (int n : {16, 4096, 1 << 20}) {
    for (double scale : {0.1, 0.5, 1.0, 2.0}) {
      const double d = 6.0;
      const double want = std::min(0.95, scale * std::pow(4.0 / (n * (d + 2.0)), 1.0 / (d + 4.0)));
      EXPECT_DOUBLE_EQ(engine::KernelBandwidth(scale, n), want);
      EXPECT_DOUBLE_EQ(engine::KernelShrinkage(want), std::sqrt(1.0 - want * want));
    }
  }
}

TEST(PfMath, LiuWestMoveIsTheCpuRowOrder) {
  std::mt19937 rng(8);
  float x[6], shift[6], root[21], z[6], out[6];
  RandomState(rng, x);
  for (float& v : shift) v = Uniform(rng, -1, 1);
  for (float& v : root) v = Uniform(rng, -0.1f, 0.1f);
  for (float& v : z) v = Uniform(rng, -2, 2);
  const float a = 0.97f;
  LiuWestMove(x, a, shift, root, z, out);
  int k = 0;
  for (int r = 0; r < 6; ++r) {  // MoveRow<r>: a src + shift, then + l(r, c) z_c for c <= r
    float v = a * x[r] + shift[r];
    for (int c = 0; c <= r; ++c) v += root[k++] * z[c];
    EXPECT_EQ(out[r], v);
  }
}

TEST(PfMath, MomentsMatchATwoPassReference) {
  std::mt19937 rng(9);
  const int n = 3000;
  std::vector<float> states(6 * n), w(n);
  float wsum = 0.0f;
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 6; ++k) states[6 * i + k] = (k < 3 ? 1000.0f : 2.0f) + Uniform(rng, -0.5f, 0.5f) * (k + 1);
    w[i] = Uniform(rng, 0.0f, 1.0f);
    wsum += w[i];
  }
  for (float& v : w) v /= wsum;
  const float* shift = &states[0];
  double sums[kMomentSums] = {};
  for (int i = 0; i < n; ++i) {
    float terms[kMomentSums];
    MomentTerms(&states[6 * i], shift, w[i], terms);
    for (int k = 0; k < kMomentSums; ++k) sums[k] += terms[k];
  }
  double mean[6], cov[36];
  FinishMoments(sums, shift, mean, cov);
  double ref_mean[6] = {}, ref_cov[36] = {}, total = 0.0;
  for (int i = 0; i < n; ++i) {
    total += w[i];
    for (int k = 0; k < 6; ++k) ref_mean[k] += w[i] * static_cast<double>(states[6 * i + k]);
  }
  for (double& v : ref_mean) v /= total;
  for (int i = 0; i < n; ++i) {
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) {
        ref_cov[r * 6 + c] += w[i] * (states[6 * i + r] - ref_mean[r]) * (states[6 * i + c] - ref_mean[c]) / total;
      }
    }
  }
  for (int r = 0; r < 6; ++r) {
    EXPECT_NEAR(mean[r], ref_mean[r], 1e-6 * std::abs(ref_mean[r]));
    for (int c = 0; c < 6; ++c) {
      EXPECT_NEAR(cov[r * 6 + c], ref_cov[r * 6 + c], 1e-5 * std::sqrt(ref_cov[r * 7] * ref_cov[c * 7]));
    }
  }
}

}  // namespace
}  // namespace localizer::gpu::pf
