// The GPU GCC stage's __host__ __device__ maths (gpu/tdoa/gcc_math.cuh and the engine's shared
// engine/tdoa/gcc_math.h, peak_math.h, core/fast_math.h), run on the host and compared with
// the engine's CPU stage on the same inputs. Compiled by nvcc, so the code under test is the
// code the kernels inline; it runs without a GPU.
//
// What is checked: the weightings per bin (against cross_spectrum.h's functors and WeighBins),
// the peak refinements (against engine::InterpolatePeak, on random windows and on real GCC
// windows), and a host emulation of the whole batched pipeline (FFTW in place of cuFFT, every
// other step through gcc_math.cuh in the order the kernels take them) against
// GccPhatEstimator::Estimate, pair by pair, including the silent frame and the quality
// fallback over the full correlation, and delay_sigma and the candidates made from the
// emulated moments kernel's sums as gcc_batch.cc makes them.

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
#include "engine/tdoa/delay_statistics.h"
#include "engine/tdoa/fftw_util.h"
#include "engine/tdoa/gcc_layout.h"
#include "engine/tdoa/gcc_phat.h"
#include "engine/tdoa/peak_interpolation.h"
#include "gpu/tdoa/gcc_math.cuh"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::gpu {
namespace {

using engine::PeakInterpolation;
using engine::Weighting;

constexpr PeakInterpolation kMethods[] = {PeakInterpolation::kParabolic, PeakInterpolation::kGaussian,
                                          PeakInterpolation::kSinc};
constexpr Weighting kWeightings[] = {Weighting::kPhat, Weighting::kPhatBeta, Weighting::kScot, Weighting::kCc};

double RelativeDifference(double a, double b) { return std::abs(a - b) / std::max({std::abs(a), std::abs(b), 1e-30}); }

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

// ---- The whole pipeline, emulated on the host ----------------------------------------------

// What the kernels compute for one frame, with FFTW standing in for cuFFT.
struct EmulatedPair {
  int peak_lag = 0;
  double offset = 0.0;
  float norm = 0.0f;
  float peak_value = 0.0f;
  float quality = 0.0f;
  bool circular = false;  // the quality came from the full-correlation fallback
  std::vector<float> gcc;
  std::vector<float> padded;  // R at lags -(L + K)..L + K, as the kernel keeps it
  double floor_samples = 0.0;
  gcc::BinMoments moments;
};

// R at lag `lag` of a correlation row: corr / S (scaled) or corr itself, as the kernel reads
// it (functors rather than lambdas: the shared templates are __host__ __device__).
struct LagReader {
  const float* corr;
  int n;
  float scale;
  LOCALIZER_HOST_DEVICE float operator()(int lag) const { return corr[engine::WrapLag(lag, n)] * scale; }
};
struct WindowReader {  // window index i is lag i - max_lag
  LagReader lags;
  int max_lag;
  LOCALIZER_HOST_DEVICE float operator()(int i) const { return lags(i - max_lag); }
};

// GccPeakKernel's steps, in its order, on one correlation row.
EmulatedPair PeakLikeTheKernel(const float* corr, int n, int max_lag, float norm, int32_t interpolation) {
  EmulatedPair out;
  out.norm = norm;
  const int count = 2 * max_lag + 1;
  if (!(norm > 0.0f)) {
    out.gcc.assign(count, 0.0f);
    return out;
  }
  const float scale = 1.0f / norm;
  const LagReader scaled{corr, n, scale};
  const WindowReader in_window{scaled, max_lag};
  gcc::PeakCandidate best = gcc::NoPeak();
  for (int i = 0; i < count; ++i) {
    out.gcc.push_back(in_window(i));
    best = gcc::BetterPeak(best, {in_window(i), i});
  }
  out.peak_lag = best.index - max_lag;
  out.peak_value = best.value;
  int first = 0, last = 0;
  engine::MainLobe(in_window, count, best.index, &first, &last);
  out.circular = !(first > 0 || last + 1 < count);
  float sidelobe = 0.0f;
  if (!out.circular) {
    for (int i = 0; i < count; ++i) {
      if (i < first || i > last) sidelobe = engine::hd::Max(sidelobe, std::abs(in_window(i)));
    }
  } else {
    const LagReader raw{corr, n, 1.0f};
    engine::CircularMainLobe(raw, n, out.peak_lag, &first, &last);
    for (int lag = last + 1; lag < first + n; ++lag) sidelobe = engine::hd::Max(sidelobe, std::abs(raw(lag)));
    sidelobe = scale * sidelobe;
  }
  float samples[engine::kPeakSamples];
  for (int m = 0; m < engine::kPeakSamples; ++m) samples[m] = scaled(out.peak_lag + m - engine::kPeakHalfWidth);
  out.offset = gcc::InterpolatePeak(interpolation, samples);
  out.floor_samples = engine::kSincFloorSamples;
  if (interpolation != gcc::kSinc) {
    const double bias = out.offset - gcc::InterpolatePeak(gcc::kSinc, samples);
    out.floor_samples = std::sqrt(bias * bias + engine::kSincFloorSamples * engine::kSincFloorSamples);
  }
  out.quality = engine::QualityRatio(out.peak_value, sidelobe);
  for (int i = -engine::kPeakHalfWidth; i < count + engine::kPeakHalfWidth; ++i) out.padded.push_back(in_window(i));
  return out;
}

// Pack, R2C, weigh, C2R (GccPackKernel, GccWeighKernel) for every pair, then the peak.
std::vector<EmulatedPair> EmulateFrame(const engine::ArrayGeometry& array, const engine::GccOptions& options,
                                       const std::vector<float>& frame) {
  const engine::GccLayout layout = *engine::ComputeGccLayout(array, options);
  const int n = layout.fft_size;
  const int bins = layout.bin_count;
  const int channels = array.sensor_count();
  engine::FftwFloats signal = engine::AllocateFftwFloats(n);
  engine::FftwFloats spectra = engine::AllocateFftwFloats(static_cast<std::size_t>(2 * bins) * channels);
  engine::FftwFloats cross = engine::AllocateFftwFloats(2 * bins);
  engine::FftwFloats corr = engine::AllocateFftwFloats(n);
  engine::FftwPlan forward = engine::PlanRealForward(n, signal.get(), spectra.get(), FFTW_ESTIMATE);
  engine::FftwPlan inverse = engine::PlanRealInverse(n, cross.get(), corr.get(), FFTW_ESTIMATE);
  std::vector<double> energy(channels, 0.0);
  for (int c = 0; c < channels; ++c) {
    for (int i = 0; i < n; ++i) {
      const float v = i < options.frame_samples ? frame[static_cast<std::size_t>(c) * options.frame_samples + i] : 0.0f;
      signal[i] = v;
      energy[c] += static_cast<double>(v) * v;
    }
    fftwf_execute_dft_r2c(forward.get(), signal.get(), engine::AsComplex(spectra.get() + 2 * bins * c));
  }
  std::vector<EmulatedPair> pairs;
  const int ref = array.reference_sensor();
  for (int p = 0; p < array.pair_count(); ++p) {
    const int k = array.sensor_of_pair(p);
    const gcc::WeighParams params = gcc::MakeWeighParams(static_cast<int32_t>(options.weighting),
                                                         static_cast<float>(options.phat_beta), energy[ref], energy[k]);
    const float* xr = spectra.get() + 2 * bins * ref;
    const float* xk = spectra.get() + 2 * bins * k;
    double half_sum = 0.0;
    for (int b = 0; b < bins; ++b) {
      engine::CrossBin g{0.0f, 0.0f};
      if (b >= layout.band_first_bin && b < layout.band_end_bin) {
        const gcc::WeighedBin w = gcc::WeighBin(params, {xr[2 * b], xr[2 * b + 1]}, {xk[2 * b], xk[2 * b + 1]});
        g = w.g;
        half_sum += w.weighted_mag;
      }
      cross[2 * b] = g.re;
      cross[2 * b + 1] = g.im;
    }
    const float norm = gcc::FullSpectrumNorm(half_sum, cross[0], cross[2 * (bins - 1)]);
    fftwf_execute(inverse.get());
    pairs.push_back(
        PeakLikeTheKernel(corr.get(), n, layout.max_lag_samples[p], norm, static_cast<int32_t>(options.interpolation)));
    // GccMomentsKernel: G recomputed from the spectra (the inverse transform destroyed cross).
    EmulatedPair& pair = pairs.back();
    if (!(norm > 0.0f)) continue;
    for (int b = layout.band_first_bin; b < layout.band_end_bin; ++b) {
      const gcc::WeighedBin w = gcc::WeighBin(params, {xr[2 * b], xr[2 * b + 1]}, {xk[2 * b], xk[2 * b + 1]});
      gcc::AddBinMoments(b, n, pair.peak_lag + pair.offset, w.g, &pair.moments);
    }
  }
  return pairs;
}

engine::ArrayGeometry ScaledTetrahedron(double scale, double sound_speed_mps) {
  std::vector<engine::Vec3> sensors = engine::testing::TetrahedronSensors();
  for (auto& s : sensors) s *= scale;
  return *engine::ArrayGeometry::Create(sensors, sound_speed_mps);
}

struct Case {
  double array_scale;
  Weighting weighting;
  PeakInterpolation interpolation;
  double band_low_hz;
  double band_high_hz;
  double snr_db;
};

// Returns how many pairs took the full-correlation quality fallback.
int ExpectEmulationMatchesCpu(const Case& c, uint64_t seed) {
  engine::testing::SignalSpec spec;  // 11025 Hz, 200..4000 Hz, 4096 samples
  const engine::ArrayGeometry array = ScaledTetrahedron(c.array_scale, 1500.0);
  engine::GccOptions options;
  options.frame_samples = spec.frame_samples;
  options.sample_rate_hz = spec.sample_rate_hz;
  options.weighting = c.weighting;
  options.interpolation = c.interpolation;
  options.band_low_hz = c.band_low_hz;
  options.band_high_hz = c.band_high_hz;
  spec.band_low_hz = c.band_low_hz > 0.0 ? c.band_low_hz : 50.0;
  spec.band_high_hz = c.band_high_hz > 0.0 ? c.band_high_hz : 4000.0;
  const auto delays = engine::testing::ChannelDelaysSamples(array, engine::Vec3(3.0, -7.0, 1.5), spec.sample_rate_hz);
  const std::vector<float> frame = engine::testing::DelayedNoiseFrame(spec, delays, c.snr_db, seed);

  auto cpu = engine::GccPhatEstimator::Create(array, options);
  EXPECT_TRUE(cpu.ok()) << cpu.status().ToString();
  if (!cpu.ok()) return 0;
  engine::Measurement m;
  EXPECT_TRUE((*cpu)->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
  const std::vector<EmulatedPair> gpu = EmulateFrame(array, options, frame);
  const float noise_floor_inverse = engine::ComputeGccLayout(array, options)->noise_floor_inverse;
  int circular = 0;
  EXPECT_EQ(gpu.size(), m.pairs.size());
  for (std::size_t p = 0; p < gpu.size() && p < m.pairs.size(); ++p) {
    SCOPED_TRACE("pair " + std::to_string(p));
    const engine::PairMeasurement& want = m.pairs[p];
    const EmulatedPair& got = gpu[p];
    const double delay_samples = got.peak_lag + got.offset;
    EXPECT_NEAR(delay_samples, want.delay_s * spec.sample_rate_hz, 1e-4);
    EXPECT_LE(RelativeDifference(got.peak_value, want.peak_value), 1e-4);
    EXPECT_LE(RelativeDifference(got.quality, want.quality), 1e-4);
    EXPECT_LE(RelativeDifference(got.peak_value * noise_floor_inverse, want.peak_snr), 1e-4);
    EXPECT_EQ(-static_cast<int>(got.gcc.size() / 2), want.first_lag_samples);
    EXPECT_EQ(got.gcc.size(), want.gcc.size());
    float worst_gcc = 0.0f;
    for (std::size_t i = 0; i < got.gcc.size() && i < want.gcc.size(); ++i) {
      worst_gcc = std::max(worst_gcc, std::abs(got.gcc[i] - want.gcc[i]));
    }
    EXPECT_LE(worst_gcc, 1e-5f);
    // delay_sigma and the candidates as gcc_batch.cc's Fill makes them from the kernels' output.
    const engine::SpectrumMoments moments{got.moments.level, got.moments.first, got.moments.curvature,
                                          got.moments.slope_var};
    const double padding = static_cast<double>(engine::ComputeGccLayout(array, options)->fft_size) / spec.frame_samples;
    const int max_lag = static_cast<int>(got.gcc.size() / 2);
    const engine::DelaySpread spread =
        engine::SpreadFromMoments(moments, got.norm, padding, got.floor_samples, max_lag);
    EXPECT_LE(RelativeDifference(spread.sigma_samples / spec.sample_rate_hz, want.delay_sigma_s), 1e-4)
        << spread.sigma_samples / spec.sample_rate_hz << " vs " << want.delay_sigma_s;
    engine::PairMeasurement picked;
    picked.delay_s = delay_samples / spec.sample_rate_hz;
    picked.peak_value = got.peak_value;
    picked.delay_sigma_s = spread.sigma_samples / spec.sample_rate_hz;
    std::vector<engine::WindowExtremum> scratch;
    engine::PickDelayCandidates(std::span<const float>(got.padded.data() + engine::kPeakHalfWidth, got.gcc.size()),
                                got.peak_lag + max_lag, max_lag, spread, c.interpolation, spec.sample_rate_hz,
                                options.max_candidates, &scratch, &picked);
    EXPECT_EQ(picked.candidates.size(), want.candidates.size());
    for (std::size_t k = 0; k < picked.candidates.size() && k < want.candidates.size(); ++k) {
      EXPECT_NEAR(picked.candidates[k].delay_s * spec.sample_rate_hz, want.candidates[k].delay_s * spec.sample_rate_hz,
                  1e-4)
          << "candidate " << k;
      EXPECT_LE(RelativeDifference(picked.candidates[k].delay_sigma_s, want.candidates[k].delay_sigma_s), 1e-3)
          << "candidate " << k;
    }
    circular += got.circular ? 1 : 0;
  }
  return circular;
}

TEST(GccMath, EmulatedPipelineEqualsGccPhatEstimator) {
  uint64_t seed = 100;
  for (Weighting w : kWeightings) {
    for (PeakInterpolation method : kMethods) {
      SCOPED_TRACE(std::string(engine::WeightingName(w)) + "/" + engine::PeakInterpolationName(method));
      ExpectEmulationMatchesCpu({1.0, w, method, 200.0, 4000.0, 20.0}, ++seed);  // in band
      ExpectEmulationMatchesCpu({1.0, w, method, 0.0, 0.0, 10.0}, ++seed);       // full band
      ExpectEmulationMatchesCpu({3.0, w, method, 500.0, 2500.0, 0.0}, ++seed);   // wide window, 0 dB
    }
  }
}

TEST(GccMath, EmulatedQualityFallbackEqualsTheCpu) {
  // A 10 cm array (windows of a few lags) under a 50..300 Hz source: plain CC's main lobe is
  // tens of samples wide, fills the window, and the quality comes from the full correlation.
  int circular = 0;
  uint64_t seed = 7;
  for (PeakInterpolation method : kMethods) {
    circular += ExpectEmulationMatchesCpu({0.05, Weighting::kCc, method, 50.0, 300.0, 30.0}, ++seed);
  }
  EXPECT_GT(circular, 0) << "no pair exercised the fallback";
}

TEST(GccMath, EmulatedSilentFrameEqualsTheCpu) {
  const engine::ArrayGeometry array = ScaledTetrahedron(1.0, 1500.0);
  engine::GccOptions options;
  options.sample_rate_hz = 11025.0;
  const std::vector<float> frame(4 * options.frame_samples, 0.0f);
  auto cpu = engine::GccPhatEstimator::Create(array, options);
  ASSERT_TRUE(cpu.ok());
  engine::Measurement m;
  ASSERT_TRUE((*cpu)->Estimate(frame.data(), options.frame_samples, 0.0, &m).ok());
  for (Weighting w : kWeightings) {
    options.weighting = w;
    const std::vector<EmulatedPair> gpu = EmulateFrame(array, options, frame);
    for (std::size_t p = 0; p < gpu.size(); ++p) {
      EXPECT_EQ(gpu[p].norm, 0.0f);
      EXPECT_EQ(gpu[p].peak_lag + gpu[p].offset, m.pairs[p].delay_s);
      EXPECT_EQ(gpu[p].quality, m.pairs[p].quality);
      EXPECT_EQ(gpu[p].peak_value, m.pairs[p].peak_value);
      EXPECT_EQ(gpu[p].gcc, m.pairs[p].gcc);
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
