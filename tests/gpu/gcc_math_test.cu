// The GPU GCC stage's __host__ __device__ maths (gpu/tdoa/gcc_math.cuh and the engine's shared
// engine/tdoa/gcc_math.h, peak_math.h, core/fast_math.h), run on the host and compared with
// the engine's CPU stage on the same inputs. Compiled by nvcc, so the code under test is the
// code the kernels inline; it runs without a GPU.
//
// What is checked: the weightings per bin (against cross_spectrum.h's functors and WeighBins),
// the peak refinements (against engine::InterpolatePeak, on random windows and on real GCC
// windows). The whole batched pipeline emulated on the host is gcc_emulation_test.cu.

// Eigen's CUDA support is for device code; this file uses Eigen on the host only.
#define EIGEN_NO_CUDA
// nvcc's front end flags engine/core/status.h's assignment of a [[nodiscard]] Status to a
// member as "ignoring return value" (g++ does not); the engine code is fine.
#pragma nv_diag_suppress 2810

#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <vector>

#include "engine/core/fast_math.h"
#include "engine/tdoa/cross_spectrum.h"
#include "engine/tdoa/gcc_phat.h"
#include "engine/tdoa/peak_interpolation.h"
#include "gpu/tdoa/gcc_math.cuh"
#include "tests/gpu/gcc_host_cases.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::gpu {
namespace {

using engine::PeakInterpolation;
using engine::Weighting;

using testing::kMethods;
using testing::kWeightings;
using testing::RelativeDifference;
using testing::ScaledTetrahedron;

// ---- Fast exp/log and the weightings --------------------------------------------------------

// The kernels weigh with the engine's own FastExp / FastLog (one copy, engine/core/fast_math.h):
// compiled here by nvcc, they stay within the same 1e-6 of the exact values that the former
// device copy was held to against the engine's (the engine's stated accuracy is 3e-7).
TEST(GccMath, FastExpAndLogEqualTheEngines) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> exponent(-90.0f, 90.0f);
  std::uniform_real_distribution<float> log_of(-80.0f, 80.0f);
  for (int i = 0; i < 100000; ++i) {
    const float x = exponent(rng);
    const double clamped = std::clamp(static_cast<double>(x), -87.0, 88.0);
    EXPECT_LE(RelativeDifference(engine::FastExp(x), std::exp(clamped)), 1e-6) << x;
    const float y = std::exp(log_of(rng));
    EXPECT_LE(std::abs(engine::FastLog(y) - std::log(static_cast<double>(y))),
              1e-6f * std::max(1.0f, std::abs(std::log(y))))
        << y;
  }
}

TEST(GccMath, FloorEqualsTheCpusClampedFloor) {
  for (double power : {0.0, 1e-300, 1e-30, 1.0, 4096.0, 1e30, 1e60, 1e300}) {
    const float cpu = static_cast<float>(
        std::clamp(engine::kRelativeFloor * power, static_cast<double>(FLT_MIN), static_cast<double>(FLT_MAX)));
    EXPECT_EQ(engine::PowerFloor(power), cpu) << power;
  }
}

// Random spectra, a tenth of the bins tiny so that the floors bite.
struct Spectra {
  std::vector<float> xr;  // interleaved
  std::vector<float> xk;
};
Spectra RandomSpectra(int bins, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> gauss(0.0f, 30.0f);
  std::uniform_int_distribution<int> tenth(0, 9);
  Spectra s{std::vector<float>(2 * bins), std::vector<float>(2 * bins)};
  for (int i = 0; i < 2 * bins; ++i) {
    s.xr[i] = gauss(rng) * (tenth(rng) == 0 ? 1e-12f : 1.0f);
    s.xk[i] = gauss(rng) * (tenth(rng) == 0 ? 1e-12f : 1.0f);
  }
  return s;
}

// The CPU's weighted bins (cross_spectrum.h) and its normaliser sum over [lo, hi).
template <typename Weight>
float CpuWeigh(const Spectra& s, int lo, int hi, const Weight& weight, std::vector<float>* g) {
  g->assign(s.xr.size(), 0.0f);
  return engine::WeighBins(s.xr.data(), s.xk.data(), lo, hi, weight, g->data());
}

TEST(GccMath, WeighBinEqualsTheCpuPerBinForEveryWeighting) {
  const int bins = 2561;
  const Spectra s = RandomSpectra(bins, 5);
  const double e_ref = 4096.0 * 900.0;  // about what these spectra's channels would hold
  const double e_sensor = 4096.0 * 700.0;
  const float beta = 0.7f;
  for (Weighting w : kWeightings) {
    SCOPED_TRACE(engine::WeightingName(w));
    const gcc::WeighParams p = gcc::MakeWeighParams(static_cast<int32_t>(w), beta, e_ref, e_sensor);
    std::vector<float> cpu;
    float cpu_sum = 0.0f;
    switch (w) {
      case Weighting::kPhat:
        cpu_sum = CpuWeigh(s, 0, bins, engine::PhatWeight{p.floor_mag}, &cpu);
        break;
      case Weighting::kPhatBeta:
        cpu_sum = CpuWeigh(s, 0, bins, engine::PhatBetaWeight{p.floor_mag, beta}, &cpu);
        break;
      case Weighting::kScot:
        cpu_sum = CpuWeigh(s, 0, bins, engine::ScotWeight{p.floor_ref_power, p.floor_sensor_power}, &cpu);
        break;
      case Weighting::kCc:
        cpu_sum = CpuWeigh(s, 0, bins, engine::CcWeight{}, &cpu);
        break;
    }
    double sum = 0.0;
    for (int b = 0; b < bins; ++b) {
      const gcc::WeighedBin wb = gcc::WeighBin(p, {s.xr[2 * b], s.xr[2 * b + 1]}, {s.xk[2 * b], s.xk[2 * b + 1]});
      const float scale = std::max({std::abs(cpu[2 * b]), std::abs(cpu[2 * b + 1]), 1e-30f});
      ASSERT_LE(std::abs(wb.g.re - cpu[2 * b]) / scale, 1e-5) << "bin " << b;
      ASSERT_LE(std::abs(wb.g.im - cpu[2 * b + 1]) / scale, 1e-5) << "bin " << b;
      sum += wb.weighted_mag;
    }
    EXPECT_LE(RelativeDifference(sum, cpu_sum), 1e-5);
  }
}

TEST(GccMath, FloorsMatchOnASilentPair) {
  // Both channels silent: every weighting gives G = 0 and S = 0, as on the CPU.
  for (Weighting w : kWeightings) {
    const gcc::WeighParams p = gcc::MakeWeighParams(static_cast<int32_t>(w), 0.8f, 0.0, 0.0);
    const gcc::WeighedBin wb = gcc::WeighBin(p, {0.0f, 0.0f}, {0.0f, 0.0f});
    EXPECT_EQ(wb.g.re, 0.0f);
    EXPECT_EQ(wb.g.im, 0.0f);
    EXPECT_EQ(wb.weighted_mag, 0.0f);
  }
  EXPECT_EQ(gcc::FullSpectrumNorm(0.0, 0.0f, 0.0f), 0.0f);
}

// ---- Peak refinement --------------------------------------------------------------------------

double EngineOffset(PeakInterpolation method, const float* samples) {
  return engine::InterpolatePeak(method, std::span<const float, engine::kPeakSamples>(samples, engine::kPeakSamples));
}

TEST(GccMath, InterpolationEqualsTheEngineOnRandomWindows) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  std::uniform_real_distribution<double> fraction(-0.5, 0.5);
  std::uniform_real_distribution<double> width(0.6, 4.0);
  int compared = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    float samples[engine::kPeakSamples];
    if (trial % 2 == 0) {  // a peak-like shape (sinc lobe) off the centre, plus noise
      const double d = fraction(rng);
      const double w = width(rng);
      for (int m = 0; m < engine::kPeakSamples; ++m) {
        const double u = (m - engine::kPeakHalfWidth - d) / w;
        const double shape = std::abs(u) < 1e-9 ? 1.0 : std::sin(std::numbers::pi * u) / (std::numbers::pi * u);
        samples[m] = static_cast<float>(shape + 0.05 * uniform(rng));
      }
    } else {  // arbitrary values, centre made the largest
      for (float& v : samples) v = uniform(rng);
      samples[engine::kPeakHalfWidth] = 1.5f;
    }
    for (PeakInterpolation method : kMethods) {
      const double gpu = gcc::InterpolatePeak(static_cast<int32_t>(method), samples);
      const double cpu = EngineOffset(method, samples);
      ASSERT_LE(std::abs(gpu - cpu), 1e-4) << engine::PeakInterpolationName(method) << " trial " << trial;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 12000);
}

// The shared three-point fits (engine/tdoa/peak_math.h, which the kernel compiles) against
// the CPU's formulas as peak_interpolation.cc wrote them with std::clamp and std::log.
double CpuParabolic(double y_minus, double y0, double y_plus) {
  const double curvature = y_minus - 2.0 * y0 + y_plus;
  if (!(curvature < 0.0)) return 0.0;
  return std::clamp(0.5 * (y_minus - y_plus) / curvature, -1.0, 1.0);
}
double CpuGaussian(double y_minus, double y0, double y_plus) {
  if (!(y_minus > 0.0 && y0 > 0.0 && y_plus > 0.0)) return CpuParabolic(y_minus, y0, y_plus);
  return CpuParabolic(std::log(y_minus), std::log(y0), std::log(y_plus));
}

TEST(GccMath, ThreePointFitsEqualTheEngine) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 2.0);
  for (int i = 0; i < 10000; ++i) {
    const double a = u(rng), b = u(rng), c = u(rng);
    EXPECT_DOUBLE_EQ(engine::ParabolicPeakOffset(a, b, c), CpuParabolic(a, b, c));
    EXPECT_NEAR(engine::GaussianPeakOffset(a, b, c), CpuGaussian(a, b, c), 1e-12);
  }
}

TEST(GccMath, PeakCombinationIsStdMaxElementWhateverTheOrder) {
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> level(0, 5);  // few levels: many ties
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<float> r(97);
    for (float& v : r) v = static_cast<float>(level(rng));
    const int expected = static_cast<int>(std::max_element(r.begin(), r.end()) - r.begin());
    // Strided partial results (as the threads of a block hold them), combined pairwise.
    for (int threads : {1, 4, 32, 128}) {
      std::vector<gcc::PeakCandidate> partial(threads, gcc::NoPeak());
      for (int i = 0; i < static_cast<int>(r.size()); ++i) {
        partial[i % threads] = gcc::BetterPeak(partial[i % threads], {r[i], i});
      }
      gcc::PeakCandidate best = gcc::NoPeak();
      for (int t = threads - 1; t >= 0; --t) best = gcc::BetterPeak(partial[t], best);
      EXPECT_EQ(best.index, expected);
    }
  }
}

TEST(GccMath, InterpolationEqualsTheEngineOnRealGccWindows) {
  // The CPU's own GCC windows: wherever the peak has 8 lags either side inside the window,
  // the device refinement of those 17 samples equals both engine::InterpolatePeak and the
  // fraction the CPU reported.
  const engine::ArrayGeometry array = ScaledTetrahedron(3.0, 1500.0);
  engine::testing::SignalSpec spec;
  int compared = 0;
  for (PeakInterpolation method : kMethods) {
    engine::GccOptions options;
    options.sample_rate_hz = spec.sample_rate_hz;
    options.band_low_hz = spec.band_low_hz;
    options.band_high_hz = spec.band_high_hz;
    options.interpolation = method;
    auto cpu = engine::GccPhatEstimator::Create(array, options);
    ASSERT_TRUE(cpu.ok());
    for (uint64_t seed = 1; seed <= 10; ++seed) {
      std::mt19937 rng(static_cast<uint32_t>(seed));
      std::uniform_real_distribution<double> coordinate(-20.0, 20.0);
      const engine::Vec3 source(coordinate(rng), coordinate(rng), coordinate(rng));
      const auto delays = engine::testing::ChannelDelaysSamples(array, source, spec.sample_rate_hz);
      const auto frame = engine::testing::DelayedNoiseFrame(spec, delays, 15.0, seed);
      engine::Measurement m;
      ASSERT_TRUE((*cpu)->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
      for (const engine::PairMeasurement& pair : m.pairs) {
        const int peak = static_cast<int>(std::max_element(pair.gcc.begin(), pair.gcc.end()) - pair.gcc.begin());
        if (peak < engine::kPeakHalfWidth || peak + engine::kPeakHalfWidth >= static_cast<int>(pair.gcc.size()))
          continue;
        const float* samples = pair.gcc.data() + peak - engine::kPeakHalfWidth;
        const double gpu = gcc::InterpolatePeak(static_cast<int32_t>(method), samples);
        EXPECT_NEAR(gpu, EngineOffset(method, samples), 1e-4);
        const double cpu_fraction = pair.delay_s * spec.sample_rate_hz - (peak + pair.first_lag_samples);
        EXPECT_NEAR(gpu, cpu_fraction, 1e-4);
        ++compared;
      }
    }
  }
  EXPECT_GE(compared, 60);
}

}  // namespace
}  // namespace localizer::gpu
