// A pair's anchor (engine/filters/pair_noise.h): the delay's standard deviation that a GCC
// peak itself states, 1 / (SNR sqrt(-g''/g)), and that a smaller peak states a wider one.
#include "engine/filters/pair_noise.h"

#include <gtest/gtest.h>

#include <cmath>

namespace localizer::engine {
namespace {

constexpr double kRateHz = 48000.0;

// A pair whose kept GCC holds a Gaussian peak of `height` and width `width_samples` at
// lag `at_samples` and, when `second_height` > 0, a second one of that height 40 lags
// later; delay_s is set at the first, peak_snr is the first's.
PairMeasurement PairWithPeaks(double height, double width_samples, double at_samples, double peak_snr,
                              double second_height = 0.0) {
  PairMeasurement pair;
  pair.first_lag_samples = -100;
  pair.gcc.assign(201, 0.0f);
  for (int i = 0; i < 201; ++i) {
    const double lag = pair.first_lag_samples + i;
    const double d1 = (lag - at_samples) / width_samples, d2 = (lag - at_samples - 40.0) / width_samples;
    pair.gcc[static_cast<size_t>(i)] =
        static_cast<float>(height * std::exp(-0.5 * d1 * d1) + second_height * std::exp(-0.5 * d2 * d2));
  }
  pair.delay_s = at_samples / kRateHz;
  pair.peak_value = height;
  pair.peak_snr = peak_snr;
  return pair;
}

// For a Gaussian peak of width w the discrete curvature over height is 2 (1 - exp(-1/(2 w^2))),
// about 1 / w^2: the anchor is w / SNR samples.
TEST(PairNoise, APeaksAnchorIsItsWidthOverItsSnr) {
  for (double width : {2.0, 3.0, 5.0}) {
    for (double snr : {4.0, 10.0, 30.0}) {
      const PairMeasurement pair = PairWithPeaks(0.5, width, 12.0, snr);
      const double expected_samples = 1.0 / (snr * std::sqrt(2.0 * (1.0 - std::exp(-0.5 / (width * width)))));
      EXPECT_NEAR(AnchorSigmaS(pair, kRateHz) * kRateHz, expected_samples, 1e-6 * expected_samples);
      EXPECT_NEAR(expected_samples, width / snr, 0.1 * width / snr);  // the continuous form
    }
  }
}

TEST(PairNoise, TheFrontEndsSigmaIsTheAnchorWhenGiven) {
  PairMeasurement pair = PairWithPeaks(0.5, 3.0, 12.0, 10.0);
  pair.delay_sigma_s = 7e-6;
  EXPECT_EQ(AnchorSigmaS(pair, kRateHz), 7e-6);
}

// Association measures a pair at a smaller peak near the track (session_impl.h): at 0.4 of
// the tallest's height, the same shape states 2.5 times its sigma.
TEST(PairNoise, ASmallerPeakStatesAWiderSigma) {
  PairMeasurement pair = PairWithPeaks(0.5, 3.0, 12.0, 10.0, /*second_height=*/0.2);
  const double tallest_s = AnchorSigmaS(pair, kRateHz);
  pair.delay_s = 52.0 / kRateHz;
  const double second_s = PeakSigmaS(pair, pair.peak_snr * 0.2 / pair.peak_value, kRateHz);
  EXPECT_NEAR(second_s / tallest_s, 2.5, 0.01);
}

// OwnPeakSigmaS reads the height at delay_s itself: the smaller peak's 2.5 x, the tallest's
// own anchor at the tallest.
TEST(PairNoise, OwnPeakSigmaReadsThePeakWhereTheDelayIs) {
  PairMeasurement pair = PairWithPeaks(0.5, 3.0, 12.0, 10.0, /*second_height=*/0.2);
  const double tallest_s = AnchorSigmaS(pair, kRateHz);
  EXPECT_NEAR(OwnPeakSigmaS(pair, kRateHz), tallest_s, 1e-6 * tallest_s);
  pair.delay_s = 52.0 / kRateHz;
  EXPECT_NEAR(OwnPeakSigmaS(pair, kRateHz) / tallest_s, 2.5, 0.01);
  pair.delay_s = 150.0 / kRateHz;  // outside the kept window
  EXPECT_EQ(OwnPeakSigmaS(pair, kRateHz), 0.0);
}

TEST(PairNoise, NoPeakThereStatesNoSigma) {
  PairMeasurement pair = PairWithPeaks(0.5, 3.0, 12.0, 10.0);
  pair.delay_s = 99.5 / kRateHz;  // the window's last lag: no neighbour on one side
  EXPECT_EQ(PeakSigmaS(pair, 10.0, kRateHz), 0.0);
  pair.delay_s = 60.0 / kRateHz;  // a lag where the GCC is ~0 and not a maximum
  EXPECT_EQ(PeakSigmaS(pair, 10.0, kRateHz), 0.0);
  pair.gcc.clear();
  EXPECT_EQ(AnchorSigmaS(pair, kRateHz), 0.0);
}

// Adaptation (pair_noise.h): one pair, anchored by its front end at 1 us, fed `frames`
// innovations of `innovation_s` against a prior whose predicted delays spread by
// `prior_sd_s`; returns the sigma the next frame would use.
double SigmaAfter(int frames, double innovation_s, double prior_sd_s) {
  Measurement m;
  m.sample_rate_hz = kRateHz;
  m.pairs.push_back(PairWithPeaks(0.5, 3.0, 12.0, 10.0));
  m.pairs[0].delay_sigma_s = 1e-6;
  PairNoise noise(0.0);
  for (int k = 0; k < frames; ++k) {
    if (noise.Select(m, 3.0) != 1) return 0.0;
    UpdateReport report;
    noise.Finish({InnovationMoments{(k % 2 ? -1.0 : 1.0) * innovation_s, prior_sd_s * prior_sd_s}}, kRateHz, &report);
  }
  noise.Select(m, 3.0);
  return noise.sigmas_s()[0];
}

// Innovations steadily 3.5 anchors off a tight prior (inside the gate): the peaks are less
// precise than they say (multipath, a whitened band the source does not fill), and the
// scale follows towards sqrt(3.5^2 - 0.5^2) = 3.46 anchors (5 % a frame).
TEST(PairNoise, PersistentExcessAgainstATightPriorRaisesTheSigma) {
  const double start_s = SigmaAfter(0, 0.0, 0.0);
  const double after_s = SigmaAfter(60, 3.5e-6, 0.5e-6);
  EXPECT_GT(after_s, 2.0 * start_s);
  EXPECT_NEAR(after_s, 3.4e-6, 0.1e-6);
}

// A track converging from a wrong start: its cloud spreads the predicted delays by 1.5 ms
// and the innovations are 3 of those (inside the gate), thousands of anchors. No noise the
// adaptation admits (8 anchors) gives that; before, one such frame set the scale to 8 and
// it took ~10 s to come down while the track, weighing its pairs 8 times too little, ran
// off in range (campaign scene 7000013). The sigma stays where it started.
TEST(PairNoise, InnovationsOnlyAWrongPriorExplainsDoNotRaiseTheSigma) {
  const double start_s = SigmaAfter(0, 0.0, 0.0);
  EXPECT_DOUBLE_EQ(SigmaAfter(5, 4.5e-3, 1.5e-3), start_s);
  // An excess just inside what the largest admissible noise gives ((4 x 8)^2 anchors^2) still counts.
  const double inside_s = std::sqrt(1.5e-3 * 1.5e-3 + 0.99 * 32.0 * 32.0 * 1e-12);
  EXPECT_GT(SigmaAfter(5, inside_s, 1.5e-3), 2.0 * start_s);
}

}  // namespace
}  // namespace localizer::engine
