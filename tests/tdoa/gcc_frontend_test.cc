// The front end's robustness features (issue 15): delay_sigma_s, delay candidates and the
// phat-coherence weighting, asserted against the simulated truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "engine/tdoa/gcc_phat.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::engine {
namespace {

using testing::DelayedNoiseFrame;
using testing::MultipathFrame;
using testing::Path;
using testing::SignalSpec;

ArrayGeometry Tetrahedron() {
  auto array = ArrayGeometry::Create(testing::TetrahedronSensors(), 1500.0);
  EXPECT_TRUE(array.ok());
  return *array;
}

GccOptions Options(const SignalSpec& spec, bool band_hint) {
  GccOptions o;
  o.sample_rate_hz = spec.sample_rate_hz;
  o.frame_samples = spec.frame_samples;
  if (band_hint) {
    o.band_low_hz = spec.band_low_hz;
    o.band_high_hz = spec.band_high_hz;
  }
  return o;
}

struct Spread {
  double error_std = 0.0;    // samples, about the true delay (rms, bias included)
  double sigma_rms = 0.0;    // samples, sqrt(mean reported sigma^2)
  double outliers = 0.0;     // share of errors beyond 1 sample
};

Spread MeasureSpread(GccPhatEstimator& gcc, const SignalSpec& spec, double snr_db, int frames,
                     uint64_t seed) {
  const std::vector<double> delays = {0.0, 3.3, -7.6, 11.45};
  double sum_sq = 0.0, sigma_sq = 0.0;
  int count = 0, outliers = 0;
  Measurement m;
  for (int f = 0; f < frames; ++f) {
    const auto frame = DelayedNoiseFrame(spec, delays, snr_db, seed + f);
    EXPECT_TRUE(gcc.Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
    for (const PairMeasurement& p : m.pairs) {
      const double e = p.delay_s * spec.sample_rate_hz - delays[p.sensor];
      if (std::abs(e) > 1.0) { ++outliers; continue; }
      sum_sq += e * e;
      const double s = p.delay_sigma_s * spec.sample_rate_hz;
      sigma_sq += s * s;
      ++count;
    }
  }
  Spread out;
  out.error_std = std::sqrt(sum_sq / count);
  out.sigma_rms = std::sqrt(sigma_sq / count);
  out.outliers = static_cast<double>(outliers) / (outliers + count);
  return out;
}

TEST(DelaySigma, Explore) {
  SignalSpec air;
  air.sample_rate_hz = 48000.0;
  air.band_low_hz = 300.0;
  air.band_high_hz = 3000.0;
  air.frame_samples = 8192;
  for (int variant = 0; variant < 4; ++variant) {
  const SignalSpec spec = variant >= 2 ? air : SignalSpec{};
  for (bool band : {true, false}) {
    for (double snr : {-10.0, -5.0, 0.0, 5.0, 10.0, 20.0}) {
      GccOptions o = Options(spec, band);
      if (variant % 2) o.interpolation = PeakInterpolation::kParabolic;
      o.lag_margin_samples = 20;
      auto gcc = std::move(*GccPhatEstimator::Create(Tetrahedron(), o));
      std::printf("variant %d ", variant);
      const Spread s = MeasureSpread(*gcc, spec, snr, 40, 1000);
      std::printf("band %d snr %5.1f  spread %.4f  sigma %.4f  ratio %.2f outliers %.3f\n", band,
                  snr, s.error_std, s.sigma_rms, s.sigma_rms / s.error_std, s.outliers);
    }
  }
  }
}

TEST(Coherence, Explore) {
  SignalSpec spec;
  spec.band_low_hz = 500.0;
  spec.band_high_hz = 2000.0;
  for (double snr : {-15.0, -10.0, -5.0, 0.0}) {
    for (int mode = 0; mode < 4; ++mode) {
      GccOptions o = Options(spec, mode == 0);
      if (mode >= 2) o.weighting = Weighting::kPhatCoherence;
      if (mode == 3) o.coherence_smoothing_bins = 0;
      auto gcc = std::move(*GccPhatEstimator::Create(Tetrahedron(), o));
      const std::vector<double> delays = {0.0, 3.3, -7.6, 11.45};
      double sum_sq = 0; int count = 0, outliers = 0;
      Measurement m;
      for (int f = 0; f < 48; ++f) {
        const auto frame = DelayedNoiseFrame(spec, delays, snr, 5000 + f);
        ASSERT_TRUE(gcc->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
        if (f < 8) continue;
        for (const PairMeasurement& p : m.pairs) {
          const double e = p.delay_s * spec.sample_rate_hz - delays[p.sensor];
          if (std::abs(e) > 1.0) { ++outliers; continue; }
          sum_sq += e * e; ++count;
        }
      }
      std::printf("snr %5.1f mode %d spread %.4f outliers %d\n", snr, mode, std::sqrt(sum_sq / count), outliers);
    }
  }
}

}  // namespace
}  // namespace localizer::engine
