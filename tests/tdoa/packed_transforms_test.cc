// Two real transforms through one complex one (engine/tdoa/packed_transforms.h) give what two
// real transforms give, to float rounding: spectra against r2c, correlations against c2r.
#include "engine/tdoa/packed_transforms.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "engine/tdoa/fftw_util.h"

namespace localizer::engine {
namespace {

constexpr int kSize = 640;  // 5 * 2^7, as NextFastFftSize gives
constexpr int kBins = kSize / 2 + 1;
// Relative to the spectrum's or correlation's largest magnitude: a few float roundings of a
// length-640 transform.
constexpr float kTolerance = 2e-6f;

std::vector<float> Noise(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> normal;
  std::vector<float> out(count);
  for (float& v : out) v = normal(rng);
  return out;
}

// r2c of x (zero padded to kSize), interleaved.
std::vector<float> RealSpectrum(const std::vector<float>& x) {
  FftwFloats in = AllocateFftwFloats(kSize);
  FftwFloats out = AllocateFftwFloats(2 * kBins);
  FftwPlan plan = PlanRealForward(kSize, in.get(), out.get(), FFTW_ESTIMATE);
  for (std::size_t i = 0; i < x.size(); ++i) in[i] = x[i];
  fftwf_execute(plan.get());
  return {out.get(), out.get() + 2 * kBins};
}

// c2r of the half spectrum g with bins outside [lo, hi) zeroed.
std::vector<float> RealInverse(const std::vector<float>& g, int lo, int hi) {
  FftwFloats in = AllocateFftwFloats(2 * kBins);
  FftwFloats out = AllocateFftwFloats(kSize);
  FftwPlan plan = PlanRealInverse(kSize, in.get(), out.get(), FFTW_ESTIMATE);
  for (int k = lo; k < hi; ++k) {
    in[2 * k] = g[2 * k];
    in[2 * k + 1] = g[2 * k + 1];
  }
  fftwf_execute(plan.get());
  return {out.get(), out.get() + kSize};
}

float LargestMagnitude(const std::vector<float>& v) {
  float best = 0.0f;
  for (float x : v) best = std::max(best, std::abs(x));
  return best;
}

TEST(PackedTransforms, TwoChannelsSpectraAreTheirRealTransforms) {
  for (const auto& [lo, hi] : {std::pair{0, kBins}, std::pair{17, 250}}) {
    PackedTransforms packed;
    ASSERT_TRUE(packed.Init(kSize, lo, hi, FFTW_ESTIMATE));
    const std::vector<float> a = Noise(500, 1), b = Noise(500, 2);  // 500 samples, zero padded
    for (int i = 0; i < 500; ++i) {
      packed.forward_input()[2 * i] = a[i];
      packed.forward_input()[2 * i + 1] = b[i];
    }
    std::vector<float> xa(2 * kBins, 0.0f), xb(2 * kBins, 0.0f);
    packed.Forward(xa.data(), xb.data());
    const std::vector<float> want_a = RealSpectrum(a), want_b = RealSpectrum(b);
    const float scale = LargestMagnitude(want_a);
    for (int k = 0; k < kBins; ++k) {
      const bool in_band = k >= lo && k < hi;
      for (int part = 0; part < 2; ++part) {
        const int i = 2 * k + part;
        EXPECT_NEAR(xa[i], in_band ? want_a[i] : 0.0f, kTolerance * scale) << "bin " << k << " part " << part;
        EXPECT_NEAR(xb[i], in_band ? want_b[i] : 0.0f, kTolerance * scale) << "bin " << k << " part " << part;
      }
    }
  }
}

TEST(PackedTransforms, TwoSpectraInvertToTheirRealCorrelations) {
  for (const auto& [lo, hi] : {std::pair{0, kBins}, std::pair{5, 200}}) {
    PackedTransforms packed;
    ASSERT_TRUE(packed.Init(kSize, lo, hi, FFTW_ESTIMATE));
    std::vector<float> ga = Noise(2 * kBins, 3), gb = Noise(2 * kBins, 4);
    // Imaginary parts at DC and Nyquist are not part of a Hermitian spectrum; c2r ignores them
    // and so must the packing.
    packed.Inverse(ga.data(), gb.data());
    const std::vector<float> want_a = RealInverse(ga, lo, hi), want_b = RealInverse(gb, lo, hi);
    const float scale = LargestMagnitude(want_a);
    for (int i = 0; i < kSize; ++i) {
      EXPECT_NEAR(packed.inverse_output()[2 * i], want_a[i], kTolerance * scale) << i;
      EXPECT_NEAR(packed.inverse_output()[2 * i + 1], want_b[i], kTolerance * scale) << i;
    }
    // One spectrum alone: the other part is zero (to rounding: a Hermitian spectrum's inverse).
    packed.Inverse(ga.data(), nullptr);
    for (int i = 0; i < kSize; ++i) {
      EXPECT_NEAR(packed.inverse_output()[2 * i], want_a[i], kTolerance * scale) << i;
      EXPECT_NEAR(packed.inverse_output()[2 * i + 1], 0.0f, kTolerance * scale) << i;
    }
  }
}

TEST(PackedTransforms, RefusesWhatItCannotPack) {
  PackedTransforms packed;
  EXPECT_FALSE(packed.Init(641, 0, 321, FFTW_ESTIMATE));          // odd size
  EXPECT_FALSE(packed.Init(kSize, 10, 10, FFTW_ESTIMATE));        // empty band
  EXPECT_FALSE(packed.Init(kSize, 0, kBins + 1, FFTW_ESTIMATE));  // past Nyquist
}

}  // namespace
}  // namespace localizer::engine
