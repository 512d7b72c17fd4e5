// The batched GPU GCC pipeline emulated on the host: FFTW in place of cuFFT, every other step
// through gpu/tdoa/gcc_math.cuh in the order the kernels take them (pack, weigh, peak,
// moments), and delay_sigma and the candidates made from the emulated moments as
// gcc_pair_measurement.cc makes them, against GccPhatEstimator::Estimate, pair by pair,
// including the silent frame and the quality fallback over the full correlation. Compiled by
// nvcc, so the maths under test is the code the kernels inline; it runs without a GPU.

// Eigen's CUDA support is for device code; this file uses Eigen on the host only.
#define EIGEN_NO_CUDA
// nvcc's front end flags engine/core/status.h's assignment of a [[nodiscard]] Status to a
// member as "ignoring return value" (g++ does not); the engine code is fine.
#pragma nv_diag_suppress 2810

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include "engine/tdoa/delay_statistics.h"
#include "engine/tdoa/fftw_util.h"
#include "engine/tdoa/gcc_layout.h"
#include "engine/tdoa/gcc_phat.h"
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
  const int edge = engine::TaperEdgeSamples(options.frame_samples, static_cast<float>(options.taper_fraction));
  for (int c = 0; c < channels; ++c) {
    for (int i = 0; i < n; ++i) {
      const float v = i < options.frame_samples ? frame[static_cast<std::size_t>(c) * options.frame_samples + i] *
                                                      engine::TaperGain(i, options.frame_samples, edge)
                                                : 0.0f;
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
    // The moments are float sums over the bins at the measured delay, which itself agrees to
    // 1e-4 sample: the sigma agrees to 1.2e-4 on this case's worst pair since the frame taper.
    EXPECT_LE(RelativeDifference(spread.sigma_samples / spec.sample_rate_hz, want.delay_sigma_s), 2e-4)
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

}  // namespace
}  // namespace localizer::gpu
