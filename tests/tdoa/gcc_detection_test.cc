// GCC-PHAT's detection statistic, peak_snr (measurement.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "engine/tdoa/gcc_phat.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::engine {
namespace {

using testing::DelayedNoiseFrame;
using testing::SignalSpec;

GccOptions Options(const SignalSpec& spec, bool band_set, double taper_fraction = GccOptions().taper_fraction) {
  GccOptions options;
  options.sample_rate_hz = spec.sample_rate_hz;
  options.frame_samples = spec.frame_samples;
  if (band_set) {  // the source's band, as a deployment would set
    options.band_low_hz = spec.band_low_hz;
    options.band_high_hz = spec.band_high_hz;
  }
  options.taper_fraction = taper_fraction;
  return options;
}

// peak_snr of every pair over `frames` frames of independent unit noise on 4 channels, sorted.
std::vector<double> SortedNoisePeakSnr(GccPhatEstimator& gcc, const SignalSpec& spec, int frames, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  std::vector<float> frame(static_cast<size_t>(4 * spec.frame_samples));
  std::vector<double> snr;
  Measurement m;
  for (int trial = 0; trial < frames; ++trial) {
    for (float& x : frame) x = noise(rng);
    EXPECT_TRUE(gcc.Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
    for (const PairMeasurement& p : m.pairs) snr.push_back(p.peak_snr);
  }
  std::sort(snr.begin(), snr.end());
  return snr;
}

// peak_snr as a detector: independent noise on every channel stays near the maximum of
// ~70 standard normals (p99 below 5), a delayed broadband source at 0 dB far above it.
TEST(GccDetection, PeakSnrSeparatesASourceFromNoise) {
  const SignalSpec spec;
  auto created = GccPhatEstimator::Create(*ArrayGeometry::Create(testing::TetrahedronSensors(), 1500.0),
                                          Options(spec, /*band_set=*/true));
  ASSERT_TRUE(created.ok());
  auto gcc = std::move(*created);
  const std::vector<double> noise_snr = SortedNoisePeakSnr(*gcc, spec, 50, 21);
  EXPECT_LT(noise_snr[noise_snr.size() * 99 / 100], 5.0);
  Measurement m;
  const auto source = DelayedNoiseFrame(spec, {0.0, 2.5, -3.0, 6.0}, 0.0, 4);
  ASSERT_TRUE(gcc->Estimate(source.data(), spec.frame_samples, 0.0, &m).ok());
  for (const PairMeasurement& p : m.pairs) EXPECT_GT(p.peak_snr, 10.0);
}

// The noise floor follows the frame's taper: a window correlates neighbouring bins, which
// widens R's noise-only spread (by about sqrt(N sum w^4 / (sum w^2)^2)), so peak_snr on
// noise alone must read the same for every taper, with the band set and without.
TEST(GccDetection, NoiseAlonePeakSnrDoesNotDependOnTheTaper) {
  const SignalSpec spec;
  const auto array = *ArrayGeometry::Create(testing::TetrahedronSensors(), 1500.0);
  for (const bool band : {true, false}) {
    std::vector<double> medians, p99s;
    for (const double taper : {0.0, 0.2, 0.5, 1.0}) {
      auto gcc = std::move(*GccPhatEstimator::Create(array, Options(spec, band, taper)));
      const std::vector<double> snr = SortedNoisePeakSnr(*gcc, spec, 100, 22);
      medians.push_back(snr[snr.size() / 2]);
      p99s.push_back(snr[snr.size() * 99 / 100]);
      std::printf("band %d taper %.1f: noise peak_snr median %.2f p99 %.2f\n", band, taper, medians.back(),
                  p99s.back());
    }
    for (size_t i = 1; i < medians.size(); ++i) {
      EXPECT_NEAR(medians[i] / medians[0], 1.0, 0.08) << "taper #" << i << " band " << band;
      EXPECT_LT(p99s[i], 5.0) << "taper #" << i << " band " << band;
    }
  }
}

}  // namespace
}  // namespace localizer::engine
