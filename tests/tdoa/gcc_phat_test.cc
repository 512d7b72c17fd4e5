#include "engine/tdoa/gcc_phat.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::engine {
namespace {

using testing::ChannelDelaysSamples;
using testing::DelayedNoiseFrame;
using testing::kNoiseless;
using testing::MultipathFrame;
using testing::Path;
using testing::SignalSpec;

constexpr double kSoundSpeedMps = 1500.0;

ArrayGeometry Tetrahedron() { return testing::TetrahedronArray(); }

// The options a deployment would use for the test source: its band, 11025 Hz.
GccOptions SourceBandOptions(const SignalSpec& spec, Weighting weighting) {
  GccOptions options;
  options.sample_rate_hz = spec.sample_rate_hz;
  options.frame_samples = spec.frame_samples;
  options.weighting = weighting;
  options.band_low_hz = spec.band_low_hz;
  options.band_high_hz = spec.band_high_hz;
  return options;
}

std::unique_ptr<GccPhatEstimator> MakeEstimator(const ArrayGeometry& array, const GccOptions& options) {
  auto gcc = GccPhatEstimator::Create(array, options);
  EXPECT_TRUE(gcc.ok()) << gcc.status().ToString();
  return gcc.ok() ? std::move(*gcc) : nullptr;
}

// Largest |estimated - true| lag over the pairs, samples.
double WorstLagError(const Measurement& m, const std::vector<double>& channel_delays, double sample_rate_hz) {
  double worst = 0.0;
  for (const PairMeasurement& pair : m.pairs) {
    worst = std::max(worst, std::abs(pair.delay_s * sample_rate_hz - channel_delays[pair.sensor]));
  }
  return worst;
}

// ---- Parsing and validation ---------------------------------------------------------------

TEST(ParseWeighting, AcceptsTheFourNames) {
  for (Weighting w : {Weighting::kPhat, Weighting::kPhatBeta, Weighting::kScot, Weighting::kCc}) {
    auto parsed = ParseWeighting(WeightingName(w));
    ASSERT_TRUE(parsed.ok());
    EXPECT_EQ(*parsed, w);
  }
}

TEST(ParseWeighting, UnknownNameListsTheValidOnes) {
  auto parsed = ParseWeighting("roth");
  ASSERT_FALSE(parsed.ok());
  EXPECT_EQ(parsed.status().code(), StatusCode::kInvalidArgument);
  for (const char* name : {"roth", "phat", "phat-beta", "scot", "cc"}) {
    EXPECT_NE(parsed.status().message().find(name), std::string::npos) << name;
  }
}

TEST(GccOptions, BadValuesAreRejectedNamingFieldAndValue) {
  GccOptions good;
  good.sample_rate_hz = 11025.0;
  ASSERT_TRUE(good.Validate().ok());
  struct Case {
    const char* field;
    const char* value;
    void (*mutate)(GccOptions&);
  };
  const Case cases[] = {
      {"frame_samples", "63", [](GccOptions& o) { o.frame_samples = 63; }},
      {"frame_samples", "2097152", [](GccOptions& o) { o.frame_samples = 1 << 21; }},
      {"sample_rate_hz", "0", [](GccOptions& o) { o.sample_rate_hz = 0.0; }},
      {"sample_rate_hz", "inf", [](GccOptions& o) { o.sample_rate_hz = std::numeric_limits<double>::infinity(); }},
      {"sample_rate_hz", "nan", [](GccOptions& o) { o.sample_rate_hz = std::numeric_limits<double>::quiet_NaN(); }},
      {"band_low_hz", "-1", [](GccOptions& o) { o.band_low_hz = -1.0; }},
      {"band_low_hz", "6000", [](GccOptions& o) { o.band_low_hz = 6000.0; }},
      {"band_high_hz", "6000", [](GccOptions& o) { o.band_high_hz = 6000.0; }},
      {"band_high_hz", "500",
       [](GccOptions& o) {
         o.band_low_hz = 1000.0;
         o.band_high_hz = 500.0;
       }},
      {"phat_beta", "1.5", [](GccOptions& o) { o.phat_beta = 1.5; }},
      {"phat_beta", "-0.1", [](GccOptions& o) { o.phat_beta = -0.1; }},
      {"taper_fraction", "1.5", [](GccOptions& o) { o.taper_fraction = 1.5; }},
      {"taper_fraction", "-0.1", [](GccOptions& o) { o.taper_fraction = -0.1; }},
      {"taper_fraction", "nan", [](GccOptions& o) { o.taper_fraction = std::nan(""); }},
      {"lag_margin_samples", "-1", [](GccOptions& o) { o.lag_margin_samples = -1; }},
  };
  const ArrayGeometry array = Tetrahedron();
  for (const Case& c : cases) {
    GccOptions options = good;
    c.mutate(options);
    const Status status = options.Validate();
    ASSERT_FALSE(status.ok()) << c.field << " " << c.value;
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(status.message().find(c.field), std::string::npos) << status.message();
    EXPECT_NE(status.message().find(c.value), std::string::npos) << status.message();
    // Create reports the same error.
    auto gcc = GccPhatEstimator::Create(array, options);
    ASSERT_FALSE(gcc.ok());
    EXPECT_EQ(gcc.status().message(), status.message());
  }
}

TEST(GccPhatEstimator, BandWithoutAnyBinIsRejected) {
  GccOptions options;
  options.sample_rate_hz = 11025.0;
  options.frame_samples = 64;  // N = 128: bins every 86 Hz
  options.band_low_hz = 1000.0;
  options.band_high_hz = 1010.0;
  auto gcc = GccPhatEstimator::Create(Tetrahedron(), options);
  ASSERT_FALSE(gcc.ok());
  EXPECT_EQ(gcc.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(gcc.status().message().find("band"), std::string::npos);
}

TEST(GccPhatEstimator, EstimateRejectsBadInputsAndLeavesTheOutputAlone) {
  const SignalSpec spec;
  auto gcc = MakeEstimator(Tetrahedron(), SourceBandOptions(spec, Weighting::kPhat));
  std::vector<float> frame = DelayedNoiseFrame(spec, {0, 1, 2, 3}, kNoiseless, 1);
  Measurement m;
  m.t_s = -1.0;

  Status status = gcc->Estimate(frame.data(), 4000, 0.5, &m);
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("frame_samples is 4000"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("4096"), std::string::npos) << status.message();

  status = gcc->Estimate(nullptr, spec.frame_samples, 0.5, &m);
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("frame"), std::string::npos);

  EXPECT_EQ(gcc->Estimate(frame.data(), spec.frame_samples, 0.5, nullptr).code(), StatusCode::kInvalidArgument);

  frame[2 * spec.frame_samples + 17] = std::numeric_limits<float>::quiet_NaN();
  status = gcc->Estimate(frame.data(), spec.frame_samples, 0.5, &m);
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("channel 2"), std::string::npos) << status.message();
  EXPECT_EQ(m.t_s, -1.0);
  EXPECT_TRUE(m.pairs.empty());
}

// ---- Accuracy, per weighting --------------------------------------------------------------

class GccWeighting : public ::testing::TestWithParam<Weighting> {};

INSTANTIATE_TEST_SUITE_P(AllWeightings, GccWeighting,
                         ::testing::Values(Weighting::kPhat, Weighting::kPhatBeta, Weighting::kScot, Weighting::kCc),
                         [](const auto& param_info) {
                           std::string name = WeightingName(param_info.param);
                           for (char& ch : name)
                             if (ch == '-') ch = '_';
                           return name;
                         });

TEST_P(GccWeighting, IntegerAndFractionalDelaysRecoveredNoiseless) {
  const SignalSpec spec;
  auto gcc = MakeEstimator(Tetrahedron(), SourceBandOptions(spec, GetParam()));
  const std::vector<std::vector<double>> delay_sets = {
      {0, 0, 5, -9}, {0, 3.5, -7.25, 12.9}, {0, -0.1, 0.3, -14.6}, {0, 14.0, -13.0, 1.75}};
  double worst = 0.0;
  Measurement m;
  for (std::size_t i = 0; i < delay_sets.size(); ++i) {
    const auto frame = DelayedNoiseFrame(spec, delay_sets[i], kNoiseless, 10 + i);
    ASSERT_TRUE(gcc->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
    worst = std::max(worst, WorstLagError(m, delay_sets[i], spec.sample_rate_hz));
  }
  // 0.02 sample: no noise, so only the frame edges (up to 15 of 4096 samples unmatched;
  // peak_interpolation.h measures their spread at 0.0012 sample) and the interpolator's
  // bias (0.0003) remain; measured worst 0.004.
  EXPECT_LT(worst, 0.02);
}

TEST_P(GccWeighting, KnownGeometryGivesKnownDelaysAtTenDb) {
  const SignalSpec spec;
  const ArrayGeometry array = Tetrahedron();
  auto gcc = MakeEstimator(array, SourceBandOptions(spec, GetParam()));
  const std::vector<Vec3> sources_m = {Vec3(30, 5, -2), Vec3(-12, 40, 8), Vec3(0.5, -0.3, 60), Vec3(-25, -25, -25),
                                       Vec3(3, 1, 0.5)};
  double worst = 0.0;
  double sum_sq = 0.0;
  int count = 0;
  Measurement m;
  for (std::size_t i = 0; i < sources_m.size(); ++i) {
    const std::vector<double> delays = ChannelDelaysSamples(array, sources_m[i], spec.sample_rate_hz);
    for (int trial = 0; trial < 4; ++trial) {
      const auto frame = DelayedNoiseFrame(spec, delays, 10.0, 100 * i + trial);
      ASSERT_TRUE(gcc->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
      // The sign convention: pair delays are the geometry's TDOA.
      const Eigen::VectorXd tdoa_s = array.Tdoa(sources_m[i]);
      for (int p = 0; p < array.pair_count(); ++p) {
        const double error = (m.pairs[p].delay_s - tdoa_s(p)) * spec.sample_rate_hz;
        worst = std::max(worst, std::abs(error));
        sum_sq += error * error;
        ++count;
      }
    }
  }
  const double rms = std::sqrt(sum_sq / count);
  const double crb = testing::TdoaCrbStdSamples(spec, 10.0);  // 0.0053 sample
  // RMS within 2x the Cramer-Rao bound: PHAT and SCOT whiten a flat spectrum and lose only a
  // little to CC (the ML weighting here); 2x leaves room for 60 draws' sampling scatter.
  EXPECT_LT(rms, 2.0 * crb);
  // Worst of 60 errors below 0.04 sample: about 4 standard deviations of the RMS bound.
  EXPECT_LT(worst, 0.04);
}

TEST_P(GccWeighting, GccIsNormalisedAndPeaksNearOneForACleanPath) {
  const SignalSpec spec;
  auto gcc = MakeEstimator(Tetrahedron(), SourceBandOptions(spec, GetParam()));
  const std::vector<double> delays = {0, 4.2, -11.0, 8.6};
  const auto frame = DelayedNoiseFrame(spec, delays, kNoiseless, 5);
  Measurement m;
  ASSERT_TRUE(gcc->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
  for (const PairMeasurement& pair : m.pairs) {
    // |R| <= 1 by construction (normalised by the sum of |G|).
    for (float r : pair.gcc) EXPECT_LE(std::abs(r), 1.0f + 1e-5f);
    // A clean delayed copy correlates to 1 but for the unmatched |d| samples at the frame
    // ends (< 0.3%) and the integer peak sitting off the true one: 0.4 sample off, the
    // 200..4000 Hz kernel cos(2 pi 2100 t) sinc(3800 t) is down to 0.86.
    EXPECT_GT(pair.peak_value, 0.8) << pair.sensor;
    EXPECT_LE(pair.peak_value, 1.0);
  }
}

// ---- The lag window -----------------------------------------------------------------------

TEST(GccPhatEstimator, PeakBeyondThePhysicalWindowIsNotPicked) {
  const SignalSpec spec;
  const ArrayGeometry array = Tetrahedron();
  const GccOptions options = SourceBandOptions(spec, Weighting::kPhat);
  auto gcc = MakeEstimator(array, options);
  // max delay 2 m / 1500 m/s * 11025 Hz = 14.7 samples: window 15 + 2 margin = 17.
  const int max_lag = 17;
  for (int p = 0; p < array.pair_count(); ++p) EXPECT_EQ(gcc->max_lag_samples(p), max_lag);

  // Sensor 1 hears a weak direct path at 5.3 samples and a strong copy at 40 samples, which
  // no source position can produce on a 2 m pair.
  const std::vector<std::vector<Path>> channels = {
      {Path{0.0, 1.0}}, {Path{5.3, 0.4}, Path{40.0, 1.0}}, {Path{-2.0, 1.0}}, {Path{3.0, 1.0}}};
  const auto frame = MultipathFrame(spec, channels, 30.0, 21);
  Measurement m;
  ASSERT_TRUE(gcc->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
  ASSERT_EQ(m.pairs.size(), 3u);
  for (const PairMeasurement& pair : m.pairs) {
    EXPECT_EQ(pair.first_lag_samples, -max_lag);
    EXPECT_EQ(pair.gcc.size(), static_cast<std::size_t>(2 * max_lag + 1));
  }
  const double lag = m.pairs[0].delay_s * spec.sample_rate_hz;
  // 0.25 sample: PHAT divides by |H| of the two-path channel, which distorts the weak
  // path's peak (measured 0.09 sample off); picking the strong copy would be 35 samples off.
  EXPECT_NEAR(lag, 5.3, 0.25);

  // The test has teeth: with a window wide enough, the strong copy wins.
  GccOptions wide = options;
  wide.lag_margin_samples = 40;
  auto wide_gcc = MakeEstimator(array, wide);
  ASSERT_TRUE(wide_gcc->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
  EXPECT_NEAR(m.pairs[0].delay_s * spec.sample_rate_hz, 40.0, 0.1);
}

TEST(GccPhatEstimator, WindowIsClampedBelowHalfTheTransform) {
  SignalSpec spec;
  spec.frame_samples = 64;  // the window is clamped to 64 + 8: N = 160 (5 * 2^5)
  GccOptions options = SourceBandOptions(spec, Weighting::kPhat);
  options.lag_margin_samples = std::numeric_limits<int>::max();  // clamps, never overflows
  auto gcc = MakeEstimator(Tetrahedron(), options);
  ASSERT_EQ(gcc->fft_size(), 160);
  EXPECT_EQ(gcc->max_lag_samples(0), 71);
  const std::vector<double> delays = {0, 2.5, -3.0, 6.0};
  const auto frame = DelayedNoiseFrame(spec, delays, kNoiseless, 3);
  Measurement m;
  ASSERT_TRUE(gcc->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
  EXPECT_EQ(m.pairs[0].gcc.size(), 143u);
  // 0.2 sample: a 64-sample frame loses up to 6 / 64 of its overlap to the delay.
  EXPECT_LT(WorstLagError(m, delays, spec.sample_rate_hz), 0.2);
}

// A 5 cm array has a window of one sample either side, all of it main lobe: quality then
// compares with the rest of the correlation.
TEST(GccPhatEstimator, QualityFallsBackToTheFullCorrelationWhenTheWindowIsAllMainLobe) {
  const SignalSpec spec;
  std::vector<Vec3> sensors = testing::TetrahedronSensors();
  for (Vec3& s : sensors) s *= 0.025;  // 5 cm edges: at most 0.37 sample of delay
  auto array = ArrayGeometry::Create(sensors, kSoundSpeedMps);
  ASSERT_TRUE(array.ok());
  GccOptions options = SourceBandOptions(spec, Weighting::kPhat);
  options.lag_margin_samples = 0;
  auto gcc = MakeEstimator(*array, options);
  EXPECT_EQ(gcc->max_lag_samples(0), 1);
  const std::vector<double> delays = ChannelDelaysSamples(*array, Vec3(10, 4, 2), spec.sample_rate_hz);
  const auto frame = DelayedNoiseFrame(spec, delays, 30.0, 8);
  Measurement m;
  ASSERT_TRUE(gcc->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
  for (const PairMeasurement& pair : m.pairs) {
    EXPECT_EQ(pair.gcc.size(), 3u);
    EXPECT_GT(pair.quality, 2.0);
    EXPECT_LT(pair.quality, 1e6);
  }
  EXPECT_LT(WorstLagError(m, delays, spec.sample_rate_hz), 0.05);
}

// ---- Band limits, quality, outputs -------------------------------------------------------

std::vector<float> WithTone(std::vector<float> frame, const SignalSpec& spec, double tone_hz, double amplitude) {
  for (std::size_t c = 0; c < frame.size() / spec.frame_samples; ++c) {
    for (int i = 0; i < spec.frame_samples; ++i) {
      frame[c * spec.frame_samples + i] +=
          static_cast<float>(amplitude * std::sin(2.0 * std::numbers::pi * tone_hz * i / spec.sample_rate_hz));
    }
  }
  return frame;
}

// A strong hum at 4800 Hz, the same on every channel (zero delay), is outside the source band
// 200..4000 Hz: with the band set it must not move the estimate.
TEST_P(GccWeighting, ToneOutsideTheBandDoesNotMoveTheEstimate) {
  const SignalSpec spec;
  const ArrayGeometry array = Tetrahedron();
  auto gcc = MakeEstimator(array, SourceBandOptions(spec, GetParam()));
  const std::vector<double> delays = ChannelDelaysSamples(array, Vec3(20, -8, 5), spec.sample_rate_hz);
  const auto clean = DelayedNoiseFrame(spec, delays, 20.0, 33);
  const auto hum = WithTone(clean, spec, 4800.0, 5.0);  // 11 dB above the source
  Measurement without_tone;
  Measurement with_tone;
  ASSERT_TRUE(gcc->Estimate(clean.data(), spec.frame_samples, 0.0, &without_tone).ok());
  ASSERT_TRUE(gcc->Estimate(hum.data(), spec.frame_samples, 0.0, &with_tone).ok());
  double moved = 0.0;
  for (int p = 0; p < array.pair_count(); ++p) {
    moved = std::max(moved, std::abs(with_tone.pairs[p].delay_s - without_tone.pairs[p].delay_s) * spec.sample_rate_hz);
  }
  // 0.01 sample: the band zeroes the tone's bins; what is left is its leakage through the
  // frame's rectangular window, about -60 dB 800 Hz away.
  EXPECT_LT(moved, 0.01);

  // Without the band the hum takes over (checked on CC, which weighs bins by power).
  if (GetParam() == Weighting::kCc) {
    GccOptions full_band = SourceBandOptions(spec, Weighting::kCc);
    full_band.band_low_hz = 0.0;
    full_band.band_high_hz = 0.0;
    auto wide = MakeEstimator(array, full_band);
    ASSERT_TRUE(wide->Estimate(hum.data(), spec.frame_samples, 0.0, &with_tone).ok());
    EXPECT_GT(WorstLagError(with_tone, delays, spec.sample_rate_hz), 0.5);
  }
}

TEST(GccPhatEstimator, QualityIsHigherAtHighSnr) {
  const SignalSpec spec;
  const ArrayGeometry array = Tetrahedron();
  auto gcc = MakeEstimator(array, SourceBandOptions(spec, Weighting::kPhat));
  const std::vector<double> delays = ChannelDelaysSamples(array, Vec3(-7, 15, 3), spec.sample_rate_hz);
  const auto mean_quality = [&](double snr_db) {
    double sum = 0.0;
    Measurement m;
    for (int trial = 0; trial < 6; ++trial) {
      const auto frame = DelayedNoiseFrame(spec, delays, snr_db, 700 + trial);
      EXPECT_TRUE(gcc->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
      for (const PairMeasurement& pair : m.pairs) sum += pair.quality;
    }
    return sum / (6.0 * array.pair_count());
  };
  const double high = mean_quality(20.0);
  const double low = mean_quality(-15.0);
  EXPECT_GT(high, 2.0 * low);
  EXPECT_GT(low, 0.0);
}

TEST(GccPhatEstimator, OutputsAreReusedAndConsistent) {
  const SignalSpec spec;
  auto gcc = MakeEstimator(Tetrahedron(), SourceBandOptions(spec, Weighting::kPhat));
  const std::vector<double> delays = {0, 6.0, -2.0, 9.0};
  const auto frame = DelayedNoiseFrame(spec, delays, 20.0, 77);
  Measurement m;
  ASSERT_TRUE(gcc->Estimate(frame.data(), spec.frame_samples, 1.25, &m).ok());
  EXPECT_EQ(m.t_s, 1.25);
  EXPECT_EQ(m.sample_rate_hz, spec.sample_rate_hz);
  const PairMeasurement* pairs = m.pairs.data();
  const float* gcc0 = m.pairs[0].gcc.data();
  ASSERT_TRUE(gcc->Estimate(frame.data(), spec.frame_samples, 2.5, &m).ok());
  EXPECT_EQ(m.pairs.data(), pairs);  // no reallocation on the second frame
  EXPECT_EQ(m.pairs[0].gcc.data(), gcc0);
  for (const PairMeasurement& pair : m.pairs) {
    EXPECT_EQ(pair.sensor, &pair - m.pairs.data() + 1);
    // peak_value is the GCC at the integer lag nearest the refined delay's integer peak.
    const int peak_lag = static_cast<int>(std::lround(delays[pair.sensor]));
    EXPECT_FLOAT_EQ(pair.gcc[peak_lag - pair.first_lag_samples], static_cast<float>(pair.peak_value));
    EXPECT_GT(pair.quality, 3.0);
  }

  GccOptions lean = SourceBandOptions(spec, Weighting::kPhat);
  lean.keep_gcc = false;
  auto no_gcc = MakeEstimator(Tetrahedron(), lean);
  ASSERT_TRUE(no_gcc->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
  for (const PairMeasurement& pair : m.pairs) EXPECT_TRUE(pair.gcc.empty());
}

TEST(GccPhatEstimator, SilentFrameGivesZerosNotNaN) {
  const SignalSpec spec;
  auto gcc = MakeEstimator(Tetrahedron(), SourceBandOptions(spec, Weighting::kPhat));
  const std::vector<float> silence(4 * spec.frame_samples, 0.0f);
  Measurement m;
  ASSERT_TRUE(gcc->Estimate(silence.data(), spec.frame_samples, 0.0, &m).ok());
  for (const PairMeasurement& pair : m.pairs) {
    EXPECT_EQ(pair.delay_s, 0.0);
    EXPECT_EQ(pair.quality, 0.0);
    EXPECT_EQ(pair.peak_value, 0.0);
    EXPECT_EQ(pair.gcc.size(), 35u);
    for (float r : pair.gcc) EXPECT_EQ(r, 0.0f);
  }
}

// FFTW_MEASURE may pick another algorithm; the answer must agree to float rounding.
TEST(GccPhatEstimator, MeasuredPlansGiveTheSameAnswer) {
  SignalSpec spec;
  spec.frame_samples = 512;
  GccOptions options = SourceBandOptions(spec, Weighting::kPhat);
  auto estimated = MakeEstimator(Tetrahedron(), options);
  options.measure_fft_plans = true;
  auto measured = MakeEstimator(Tetrahedron(), options);
  const auto frame = DelayedNoiseFrame(spec, {0, 1.3, -4.4, 7.7}, 20.0, 4);
  Measurement a;
  Measurement b;
  ASSERT_TRUE(estimated->Estimate(frame.data(), spec.frame_samples, 0.0, &a).ok());
  ASSERT_TRUE(measured->Estimate(frame.data(), spec.frame_samples, 0.0, &b).ok());
  for (int p = 0; p < 3; ++p) {
    EXPECT_NEAR(a.pairs[p].delay_s * spec.sample_rate_hz, b.pairs[p].delay_s * spec.sample_rate_hz, 1e-4);
  }
}

// FFTW's planner is not thread-safe; Create and destruction on many threads must be.
TEST(GccPhatEstimator, CreateAndDestroyOnManyThreads) {
  const ArrayGeometry array = Tetrahedron();
  std::vector<std::thread> threads;
  std::atomic<int> failures{0};
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      GccOptions options;
      options.sample_rate_hz = 11025.0;
      for (int i = 0; i < 20; ++i) {
        options.frame_samples = 64 << ((t + i) % 5);
        if (!GccPhatEstimator::Create(array, options).ok()) ++failures;
      }
    });
  }
  for (std::thread& th : threads) th.join();
  EXPECT_EQ(failures.load(), 0);
}

}  // namespace
}  // namespace localizer::engine
