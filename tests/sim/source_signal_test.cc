#include "engine/sim/source_signal.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "engine/sim/band_pass_fir.h"

namespace localizer::engine {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

double Db(double power_ratio) { return 10.0 * std::log10(power_ratio); }

// |H(f)| of an FIR.
double Gain(const std::vector<double>& taps, double f_hz, double fs_hz) {
  std::complex<double> sum = 0.0;
  for (size_t n = 0; n < taps.size(); ++n) {
    sum += taps[n] * std::polar(1.0, -kTwoPi * f_hz * static_cast<double>(n) / fs_hz);
  }
  return std::abs(sum);
}

// Mean power of x near f_hz: Hann-windowed periodogram averaged over 1024-sample segments.
double PowerNear(const std::vector<double>& x, double f_hz, double fs_hz) {
  const int segment = 1024;
  double total = 0.0;
  int count = 0;
  for (size_t start = 0; start + segment <= x.size(); start += segment, ++count) {
    std::complex<double> sum = 0.0;
    for (int n = 0; n < segment; ++n) {
      const double hann = 0.5 - 0.5 * std::cos(kTwoPi * n / segment);
      sum += hann * x[start + n] * std::polar(1.0, -kTwoPi * f_hz * n / fs_hz);
    }
    total += std::norm(sum);
  }
  return total / count;
}

SimOptions BroadbandOptions() {
  SimOptions o;
  o.sample_rate_hz = 11025.0;
  o.band_low_hz = 300.0;
  o.band_high_hz = 3000.0;
  o.seed = 42;
  return o;
}

TEST(BandPassFir, IsLinearPhaseWithTheDocumentedLength) {
  const BandPassFir water = DesignBandPassFir(300.0, 3000.0, 11025.0);
  EXPECT_EQ(water.taps.size(), 269u);
  EXPECT_DOUBLE_EQ(water.transition_hz, 150.0);
  EXPECT_EQ(DesignBandPassFir(300.0, 8000.0, 48000.0).taps.size(), 1161u);
  for (size_t n = 0; n < water.taps.size(); ++n) {
    EXPECT_DOUBLE_EQ(water.taps[n], water.taps[water.taps.size() - 1 - n]);
  }
}

TEST(BandPassFir, PassesTheBandAndStopsTheRest) {
  const double fs = 11025.0;
  const BandPassFir fir = DesignBandPassFir(300.0, 3000.0, fs);
  const double half_transition = 0.5 * fir.transition_hz;
  const double pass_low = 300.0 + half_transition, pass_high = 3000.0 - half_transition;
  for (int k = 0; pass_low + 7.0 * k <= pass_high; ++k) {
    const double f = pass_low + 7.0 * k;
    EXPECT_NEAR(20.0 * std::log10(Gain(fir.taps, f, fs)), 0.0, 0.01) << f << " Hz";
  }
  for (int k = 0; 3.0 * k <= 300.0 - half_transition; ++k) {
    const double f = 3.0 * k;
    EXPECT_LT(20.0 * std::log10(Gain(fir.taps, f, fs)), -59.0) << f << " Hz";
  }
  const double stop_low = 3000.0 + half_transition;
  for (int k = 0; stop_low + 7.0 * k <= fs / 2; ++k) {
    const double f = stop_low + 7.0 * k;
    EXPECT_LT(20.0 * std::log10(Gain(fir.taps, f, fs)), -59.0) << f << " Hz";
  }
  // The -6 dB points are the band edges.
  EXPECT_NEAR(Gain(fir.taps, 300.0, fs), 0.5, 0.01);
  EXPECT_NEAR(Gain(fir.taps, 3000.0, fs), 0.5, 0.01);
}

TEST(BandPassFir, LowPassWhenTheLowEdgeIsZero) {
  const BandPassFir fir = DesignBandPassFir(0.0, 2000.0, 11025.0);
  EXPECT_NEAR(Gain(fir.taps, 0.0, 11025.0), 1.0, 1e-3);
  EXPECT_LT(Gain(fir.taps, 3000.0, 11025.0), 1e-3);
}

TEST(SourceSignal, BroadbandNoiseHasUnitRmsAndStaysInItsBand) {
  const SimOptions o = BroadbandOptions();
  const SourceWaveform s = MakeSourceWaveform(o, -0.5, 10.0);
  double power = 0.0;
  for (double v : s.samples) power += v * v;
  power /= static_cast<double>(s.samples.size());
  // Unit RMS in expectation; 10 s of a 2700 Hz band estimates the power within ~1 %.
  EXPECT_NEAR(std::sqrt(power), 1.0, 0.02);
  const double in_band =
      std::min(PowerNear(s.samples, 1000.0, o.sample_rate_hz), PowerNear(s.samples, 2000.0, o.sample_rate_hz));
  for (double f_hz : {50.0, 150.0, 3300.0, 4500.0, 5400.0}) {
    EXPECT_LT(Db(PowerNear(s.samples, f_hz, o.sample_rate_hz) / in_band), -55.0) << f_hz;
  }
}

TEST(SourceSignal, SamplesDependOnEmissionTimeNotOnTheSpan) {
  const SimOptions o = BroadbandOptions();
  const SourceWaveform a = MakeSourceWaveform(o, -0.1, 1.0);
  const SourceWaveform b = MakeSourceWaveform(o, -1.3, 4.0);
  ASSERT_EQ(a.origin_index, static_cast<int64_t>(std::ceil(0.1 * o.sample_rate_hz)));
  for (int64_t n = -1000; n < 10000; ++n) {
    ASSERT_EQ(a.samples[a.origin_index + n], b.samples[b.origin_index + n]) << n;
  }
}

TEST(SourceSignal, SeedSelectsTheSignal) {
  SimOptions o = BroadbandOptions();
  const SourceWaveform a = MakeSourceWaveform(o, 0.0, 1.0);
  EXPECT_EQ(a.samples, MakeSourceWaveform(o, 0.0, 1.0).samples);
  o.seed = 43;
  const SourceWaveform b = MakeSourceWaveform(o, 0.0, 1.0);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  int equal = 0;
  for (size_t n = 0; n < a.samples.size(); ++n) equal += a.samples[n] == b.samples[n];
  EXPECT_EQ(equal, 0);
}

TEST(SourceSignal, ClickPulseIsBandLimitedWithUnitPeak) {
  const ClickPulse g(300.0, 3000.0);
  EXPECT_NEAR(g.duration_s(), 6.0 / 2700.0, 1e-15);
  EXPECT_DOUBLE_EQ(g(0.0), 1.0);
  EXPECT_EQ(g(0.5 * g.duration_s()), 0.0);
  EXPECT_EQ(g(-0.6 * g.duration_s()), 0.0);
  // Its spectrum by numerical integration: the main lobe fills [300, 3000] Hz; 10 % of the
  // bandwidth beyond the edges it is 50 dB down.
  const auto spectrum = [&](double f_hz) {
    const int steps = 4000;
    const double dt = g.duration_s() / steps;
    std::complex<double> sum = 0.0;
    for (int i = 0; i <= steps; ++i) {
      const double t = -0.5 * g.duration_s() + i * dt;
      sum += g(t) * std::polar(dt, -kTwoPi * f_hz * t);
    }
    return std::abs(sum);
  };
  const double peak = spectrum(g.centre_hz());
  for (int k = 0; k <= 3; ++k) {  // 0, 10, 20, 30 Hz
    const double f_hz = 10.0 * k;
    EXPECT_LT(20.0 * std::log10(spectrum(f_hz) / peak), -50.0) << f_hz;
  }
  for (int k = 0; 3270.0 + 50.0 * k <= 5512.0; ++k) {  // 3270, 3320, ..., 5470 Hz
    const double f_hz = 3270.0 + 50.0 * k;
    EXPECT_LT(20.0 * std::log10(spectrum(f_hz) / peak), -50.0) << f_hz;
  }
}

TEST(SourceSignal, ClicksComeAtTheRateWithBoundedJitter) {
  SimOptions o = BroadbandOptions();
  o.signal = SourceSignal::kClicks;
  o.click_rate_hz = 20.0;
  const std::vector<double> times = ClickEmissionTimes(o, 0.0, 10.0);
  EXPECT_NEAR(static_cast<double>(times.size()), 200.0, 1.0);
  double largest_jitter = 0.0;
  for (size_t i = 0; i < times.size(); ++i) {
    const double nominal_s = std::round(times[i] * o.click_rate_hz) / o.click_rate_hz;
    largest_jitter = std::max(largest_jitter, std::abs(times[i] - nominal_s) * o.click_rate_hz);
    if (i > 0) {
      EXPECT_GE(times[i] - times[i - 1], 0.6 / o.click_rate_hz);
    }
  }
  EXPECT_LE(largest_jitter, 0.2);
  EXPECT_GT(largest_jitter, 0.1);  // it is jittered

  const SourceWaveform s = MakeSourceWaveform(o, 0.0, 10.0);
  const double peak = *std::max_element(s.samples.begin(), s.samples.end());
  EXPECT_LE(peak, 1.0);
  EXPECT_GT(peak, 0.85);  // a sampled peak is at most half a sample off the pulse's centre
  // Every click drawn is reported, including those straddling the span's ends.
  EXPECT_GE(s.click_times_s.size(), times.size());
}

// A low-pass source (band_low_hz = 0): unit RMS, DC and low frequencies pass, above the edge
// is stopped.
TEST(SourceSignal, LowPassSourceHasUnitRmsAndStaysBelowItsEdge) {
  SimOptions o = BroadbandOptions();
  o.band_low_hz = 0.0;
  o.band_high_hz = 2000.0;
  ASSERT_TRUE(o.Validate().ok());
  const SourceWaveform s = MakeSourceWaveform(o, 0.0, 10.0);
  double power = 0.0;
  for (double v : s.samples) power += v * v;
  EXPECT_NEAR(std::sqrt(power / static_cast<double>(s.samples.size())), 1.0, 0.02);
  const double in_band =
      std::min(PowerNear(s.samples, 100.0, o.sample_rate_hz), PowerNear(s.samples, 1500.0, o.sample_rate_hz));
  for (double f_hz : {2600.0, 3500.0, 5000.0}) {
    EXPECT_LT(Db(PowerNear(s.samples, f_hz, o.sample_rate_hz) / in_band), -55.0) << f_hz;
  }
}

// Tonal plus broadband: each tone carries tone_power_fraction / tone_count of the unit power
// at its drawn frequency (inside the band), the total stays 1.
TEST(SourceSignal, TonesCarryTheirShareOfThePowerAtTheirFrequencies) {
  SimOptions o = BroadbandOptions();
  o.signal = SourceSignal::kTonalBroadband;
  o.tone_count = 3;
  o.tone_power_fraction = 0.6;
  ASSERT_TRUE(o.Validate().ok());
  const std::vector<Tone> tones = SourceTones(o);
  ASSERT_EQ(tones.size(), 3u);
  const SourceWaveform s = MakeSourceWaveform(o, 0.0, 10.0);
  double power = 0.0;
  for (double v : s.samples) power += v * v;
  EXPECT_NEAR(power / static_cast<double>(s.samples.size()), 1.0, 0.03);
  for (const Tone& tone : tones) {
    EXPECT_GE(tone.frequency_hz, 300.0 + 0.1 * 2700.0);
    EXPECT_LE(tone.frequency_hz, 3000.0 - 0.1 * 2700.0);
    // Projection on the tone over 10 s: the broadband part adds ~1/sqrt(N) of noise.
    std::complex<double> sum = 0.0;
    for (size_t n = 0; n < s.samples.size(); ++n) {
      const double t_s = static_cast<double>(static_cast<int64_t>(n) - s.origin_index) / o.sample_rate_hz;
      sum += s.samples[n] * std::polar(1.0, -kTwoPi * tone.frequency_hz * t_s);
    }
    const double amplitude = 2.0 * std::abs(sum) / static_cast<double>(s.samples.size());
    EXPECT_NEAR(amplitude * amplitude / 2.0, 0.6 / 3.0, 0.01) << tone.frequency_hz;
  }
  o.signal = SourceSignal::kBroadband;
  EXPECT_TRUE(SourceTones(o).empty());
}

}  // namespace
}  // namespace localizer::engine
