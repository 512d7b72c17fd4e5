// The impulsive-noise front end (despike.h): harmless on Gaussian frames, decisive under
// alpha-stable impulses, and safe on an impulsive source.
#include "engine/tdoa/despike.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "engine/sim/alpha_stable.h"
#include "engine/sim/simulator.h"
#include "engine/tdoa/gcc_phat.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::engine {
namespace {

using testing::DelayedNoiseFrame;
using testing::SignalSpec;

ArrayGeometry Tetrahedron() { return testing::TetrahedronArray(); }

std::unique_ptr<GccPhatEstimator> BandEstimator(const SignalSpec& spec) {
  GccOptions o;
  o.sample_rate_hz = spec.sample_rate_hz;
  o.frame_samples = spec.frame_samples;
  o.band_low_hz = spec.band_low_hz;
  o.band_high_hz = spec.band_high_hz;
  auto gcc = GccPhatEstimator::Create(Tetrahedron(), o);
  EXPECT_TRUE(gcc.ok());
  return std::move(*gcc);
}

// Alpha-stable impulses (alpha 1.5, symmetric, scale `scale`) on a share `rate` of the samples,
// drawn independently per channel and sample.
void AddImpulses(std::vector<float>* frame, double rate, double scale, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution hit(rate);
  const AlphaStable impulse{1.5, 0.0, scale, 0.0};
  for (float& x : *frame) {
    if (hit(rng)) x += static_cast<float>(SampleAlphaStable(impulse, rng));
  }
}

struct Errors {
  double rms = 0.0;        // samples, all pairs and frames
  double far_share = 0.0;  // share more than one sample off
};

// rms TDOA error over `frames` frames of a 10 dB source, optionally with impulses and the
// despiker.
Errors Measure(bool impulses, bool despike, int frames, int coincidence = 0) {
  const SignalSpec spec;
  auto gcc = BandEstimator(spec);
  const std::vector<double> delays = {0.0, 3.3, -7.6, 11.45};
  const double snr_db = 10.0;
  const double noise_std = std::pow(10.0, -snr_db / 20.0);
  DespikeScratch scratch;
  double sum_sq = 0.0;
  int far = 0, count = 0;
  Measurement m;
  for (int f = 0; f < frames; ++f) {
    auto frame = DelayedNoiseFrame(spec, delays, snr_db, 300 + f);
    if (impulses) AddImpulses(&frame, 0.01, 30.0 * noise_std, 900 + f);
    if (despike) {
      EXPECT_TRUE(Despike(DespikeOptions{5.0, coincidence}, frame.data(), 4, spec.frame_samples, &scratch).ok());
    }
    EXPECT_TRUE(gcc->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
    for (const PairMeasurement& p : m.pairs) {
      const double e = p.delay_s * spec.sample_rate_hz - delays[p.sensor];
      sum_sq += e * e;
      far += std::abs(e) > 1.0;
      ++count;
    }
  }
  return {std::sqrt(sum_sq / count), static_cast<double>(far) / count};
}

TEST(Despike, OptionsAndArgumentsAreValidated) {
  std::vector<float> frame(64, 1.0f);
  for (double bad : {-1.0, 0.5, 2e6, std::nan("")}) {
    const Status s = Despike(DespikeOptions{bad}, frame.data(), 1, 64, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find("despike_k"), std::string::npos) << s.message();
  }
  EXPECT_EQ(Despike(DespikeOptions{}, nullptr, 1, 64, nullptr).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(Despike(DespikeOptions{}, frame.data(), 0, 64, nullptr).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(Despike(DespikeOptions{}, frame.data(), 1, 0, nullptr).code(), StatusCode::kInvalidArgument);
}

TEST(Despike, ClipsAtKRobustStandardDeviationsPerChannel) {
  // Channel 0: N(0, 1) with one spike of 100; channel 1: N(0, 4^2); k = 5.
  std::mt19937_64 rng(3);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  const int n = 20000;
  std::vector<float> frame(2 * n);
  for (int i = 0; i < n; ++i) frame[i] = gauss(rng);
  for (int i = 0; i < n; ++i) frame[n + i] = 4.0f * gauss(rng);
  frame[123] = 100.0f;
  frame[n + 7] = -1000.0f;
  DespikeStats stats;
  ASSERT_TRUE(Despike(DespikeOptions{}, frame.data(), 2, n, nullptr, &stats).ok());
  // The MAD from 256 evenly spaced samples estimates sigma to ~8 % (1 sd): clip levels 5
  // and 20 within 3 of those sd.
  EXPECT_NEAR(frame[123], 5.0f, 1.2f);
  EXPECT_NEAR(frame[n + 7], -20.0f, 4.8f);
  // Gaussian samples beyond 5 sigma: 5.7e-7 of them, so only the two spikes (and rarely one more).
  EXPECT_GE(stats.clipped_samples, 2);
  EXPECT_LE(stats.clipped_samples, 4);
  // k = 0 is off.
  frame[5] = 1e6f;
  ASSERT_TRUE(Despike(DespikeOptions{0.0}, frame.data(), 2, n, nullptr, &stats).ok());
  EXPECT_EQ(frame[5], 1e6f);
  EXPECT_EQ(stats.clipped_samples, 0);
}

// DespikedFrame reads a frame with nothing to clip where it is, and otherwise hands back a
// copy clipped exactly as Despike clips in place, leaving the input as it was.
TEST(Despike, DespikedFrameCopiesOnlyAFrameWithSomethingToClip) {
  std::mt19937_64 rng(11);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  const int channels = 4, n = 4096;
  std::vector<float> frame(static_cast<size_t>(channels) * n);
  for (float& x : frame) x = gauss(rng);
  const DespikeOptions options{8.0};  // 8 sigma: no Gaussian sample of these reaches it
  DespikeScratch scratch;
  std::vector<float> clipped;
  DespikeStats stats;
  auto read = DespikedFrame(options, frame.data(), channels, n, &scratch, &clipped, &stats);
  ASSERT_TRUE(read.ok());
  EXPECT_EQ(*read, frame.data());
  EXPECT_TRUE(clipped.empty());
  EXPECT_EQ(stats.clipped_samples, 0);

  AddImpulses(&frame, 0.01, 30.0, 12);
  const std::vector<float> input = frame;
  read = DespikedFrame(options, frame.data(), channels, n, &scratch, &clipped, &stats);
  ASSERT_TRUE(read.ok());
  EXPECT_EQ(*read, clipped.data());
  EXPECT_EQ(frame, input);  // untouched
  std::vector<float> in_place = input;
  DespikeStats in_place_stats;
  ASSERT_TRUE(Despike(options, in_place.data(), channels, n, &scratch, &in_place_stats).ok());
  EXPECT_EQ(clipped, in_place);
  EXPECT_EQ(stats.clipped_samples, in_place_stats.clipped_samples);
  EXPECT_GT(stats.clipped_samples, 0);

  EXPECT_EQ(DespikedFrame(options, frame.data(), channels, n, &scratch, nullptr).status().code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(DespikedFrame(options, nullptr, channels, n, &scratch, &clipped).status().code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(DespikedFrame(DespikeOptions{0.0}, frame.data(), channels, n, &scratch, &clipped).value(), frame.data());
}

// On Gaussian frames the despiker changes nothing that matters: the spread moves < 5 %.
TEST(Despike, GaussianSceneIsUnchanged) {
  const Errors without = Measure(false, false, 30);
  const Errors with = Measure(false, true, 30);
  std::printf("gaussian: rms %.5f without, %.5f with\n", without.rms, with.rms);
  EXPECT_LT(std::abs(with.rms / without.rms - 1.0), 0.05);
}

// Alpha-stable impulses (1 % of samples, 30x the noise) wreck plain GCC-PHAT; despiked, the
// spread returns to within 1.5x of the impulse-free scene and is > 20x smaller than without.
TEST(Despike, AlphaStableImpulsesAreTamed) {
  const Errors clean = Measure(false, false, 30);
  const Errors without = Measure(true, false, 30);
  const Errors with = Measure(true, true, 30);
  std::printf("impulses: rms %.4f (%.0f %% > 1 sample) without, %.4f (%.0f %%) with; clean %.4f\n", without.rms,
              100 * without.far_share, with.rms, 100 * with.far_share, clean.rms);
  EXPECT_GT(without.far_share, 0.03);  // the scene is bad without the despiker
  EXPECT_GT(without.rms, 1.0);
  EXPECT_EQ(with.far_share, 0.0);
  EXPECT_LT(with.rms, 1.5 * clean.rms);
  EXPECT_GT(without.rms, 50.0 * with.rms);
  // With the coincidence gate (window 20 samples, the tetrahedron's 15 + 5) a few impulses that
  // happen to line up on every channel survive.
  const Errors gated = Measure(true, true, 30, 20);
  std::printf("impulses, coincidence gate 20: rms %.4f (%.0f %%)\n", gated.rms, 100 * gated.far_share);
  EXPECT_EQ(gated.far_share, 0.0);
  EXPECT_LT(gated.rms, 2.0 * clean.rms);
  // A large array's window (170 samples: 15 m of water at 16 kHz) makes independent impulses
  // line up on every channel by chance about 90 % of the time at this rate; the gate, which
  // kept them all before it compared against chance, must see that it cannot tell and clip.
  const Errors wide = Measure(true, true, 30, 170);
  std::printf("impulses, coincidence gate 170: rms %.4f (%.0f %%)\n", wide.rms, 100 * wide.far_share);
  EXPECT_EQ(wide.far_share, 0.0);
  EXPECT_LT(wide.rms, 2.0 * clean.rms);
}

// A click train is an impulsive *source*, the same on every channel but delayed: clipping it
// alike on each channel keeps the delays.
TEST(Despike, ClickTrainSourceKeepsItsDelays) {
  const ArrayGeometry array = Tetrahedron();
  SimOptions sim;
  sim.signal = SourceSignal::kClicks;
  sim.duration_s = 2.0;
  sim.snr_db = 20.0;
  sim.band_low_hz = 300.0;
  sim.band_high_hz = 3000.0;
  sim.trajectory.position_m = Vec3(12.0, -5.0, 3.0);
  auto result = Simulate(array, sim);
  ASSERT_TRUE(result.ok()) << result.status().ToString();
  GccOptions o;
  o.sample_rate_hz = sim.sample_rate_hz;
  o.frame_samples = 4096;
  o.band_low_hz = sim.band_low_hz;
  o.band_high_hz = sim.band_high_hz;
  auto gcc = std::move(*GccPhatEstimator::Create(array, o));
  const Eigen::VectorXd tdoa_s = array.Tdoa(sim.trajectory.position_m);
  const int64_t total = result->samples_per_channel;
  std::vector<float> frame(4 * o.frame_samples);
  DespikeScratch scratch;
  double worst_with = 0.0, worst_without = 0.0, worst_gated = 0.0;
  int clipped = 0;
  Measurement m;
  for (int64_t start = 0; start + o.frame_samples <= total; start += o.frame_samples) {
    for (int c = 0; c < 4; ++c) {
      std::copy_n(result->samples.begin() + c * total + start, o.frame_samples, frame.begin() + c * o.frame_samples);
    }
    ASSERT_TRUE(gcc->Estimate(frame.data(), o.frame_samples, 0.0, &m).ok());
    for (int p = 0; p < 3; ++p) {
      worst_without = std::max(worst_without, std::abs(m.pairs[p].delay_s - tdoa_s(p)) * o.sample_rate_hz);
    }
    DespikeStats stats;
    std::vector<float> gated_frame = frame;
    ASSERT_TRUE(Despike(DespikeOptions{5.0, 20}, gated_frame.data(), 4, o.frame_samples, &scratch).ok());
    ASSERT_TRUE(gcc->Estimate(gated_frame.data(), o.frame_samples, 0.0, &m).ok());
    for (int p = 0; p < 3; ++p) {
      worst_gated = std::max(worst_gated, std::abs(m.pairs[p].delay_s - tdoa_s(p)) * o.sample_rate_hz);
    }
    ASSERT_TRUE(Despike(DespikeOptions{}, frame.data(), 4, o.frame_samples, &scratch, &stats).ok());
    clipped += stats.clipped_samples;
    ASSERT_TRUE(gcc->Estimate(frame.data(), o.frame_samples, 0.0, &m).ok());
    for (int p = 0; p < 3; ++p) {
      worst_with = std::max(worst_with, std::abs(m.pairs[p].delay_s - tdoa_s(p)) * o.sample_rate_hz);
    }
  }
  std::printf("clicks: worst error %.4f without, %.4f with (%d samples clipped), %.4f gated\n", worst_without,
              worst_with, clipped, worst_gated);
  EXPECT_GT(clipped, 0);  // the clicks were clipped ...
  // ... which distorts them a little differently per channel (each has its own clip level and
  // sampling phase): measured 0.25 sample worst against 0.025 unclipped, still far inside the
  // pulse's main lobe (6 samples) ...
  EXPECT_LT(worst_with, 0.5);
  // ... and the coincidence gate keeps the clicks whole: as good as no despiker at all.
  EXPECT_LT(worst_gated, 0.05);
}

}  // namespace
}  // namespace localizer::engine
