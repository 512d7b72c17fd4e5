// Source presence and position bounds on the real XAV recordings (Mouy et al. 2023): 6
// hydrophones, 32 kHz, 17 s of fish calls in 8 m of water. There is no ground truth, so
// the checks are the contract that needs none:
//   - every value is finite;
//   - no estimate flagged present lies outside the water column (the array file's bounds:
//     surface z = 7.03 m, bottom z = -0.97 m; x and y open);
//   - some frames are present, and the calls are heard: of the frames an independent
//     detector calls loud (50-1000 Hz band energy on hydrophone 3, the authors' detector
//     channel, above 8 x its running median over +-1.5 s), at least 80 % are flagged present;
//   - with the channels shifted in time against each other (0, 1.3, 2.6, ... s, circularly:
//     the same spectra, no source coherent across the array) almost no frame is present
//     (the test is set for 1e-3 false alarms per frame).
//   - on independent white noise no frame is present, with PHAT and with PHAT-coherence (it
//     was 260 of 264 with PHAT-coherence while its peak_snr used PHAT's noise scale).
// "Absent between calls" is not asserted on the real channels: between the calls the
// array hears a coherent sound field whose delays hold still to a tenth of a sample for
// seconds (a distant source; see ACCURACY.md, "XAV recordings: presence and bounds"), and
// the shifted-channel null is what checks that presence is not raised by noise.
// Measured (ACCURACY.md): calls heard 22/25 (PHAT 50-1000 Hz), 25/25 (PHAT, whole band),
// 25/25 (PHAT-coherence); shifted channels 0/264 present with PHAT.
// PHAT-coherence on the shifted channels is not asserted: a 117-125 Hz line stays coherent
// across the shifts (magnitude-squared coherence 0.58-0.87 between hydrophone 3 and 1, 2, 4;
// every other bin < 0.25), the learnt weights find it, and frames are present at
// 1.0-1.6 x the threshold (84 of 264 in the final build). A steady tone is a coherent source;
// it has no delay to give.
// Fixed since it was written: a collapsed particle cloud coasting through the bottom (11
// present frames below it with PHAT 50-1000 Hz); particles are now put back on the wall.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "clients/io/track_runner.h"
#include "clients/io/wav_io.h"
#include "clients/io/xav_array.h"
#include "engine/pipeline/session.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

constexpr int kFrame = 4096;
constexpr int kHop = 2048;
constexpr double kCallRatio = 8.0;  // band energy above this x running median: a call
constexpr double kMedianHalfWindowS = 1.5;
constexpr double kMinCallsHeard = 0.8;  // measured 0.88 (PHAT 50-1000 Hz), 1.0 otherwise
constexpr int kDetectorChannel = 3;     // detection_config_large_array.yaml: channel 3

struct Xav {
  XavArray array;
  Recording recording;
};

const Xav& LoadXav() {
  static const Xav* xav = [] {
    auto* out = new Xav;
    auto array = ReadXavHydrophoneCsv(testing::XavConfigCsv());
    EXPECT_TRUE(array.ok()) << array.status().ToString();
    if (!array.ok()) return out;
    out->array = *array;
    auto paths = FindXavRecordings(testing::XavDir(), array->file_name_roots);
    EXPECT_TRUE(paths.ok()) << paths.status().ToString();
    if (!paths.ok()) return out;
    std::string warning;
    auto recording = ReadWavSet(*paths, &warning);
    EXPECT_TRUE(recording.ok()) << recording.status().ToString();
    if (recording.ok()) out->recording = std::move(*recording);
    return out;
  }();
  return *xav;
}

// Each channel rotated by channel x 1.3 s.
Recording Shifted(const Recording& in) {
  Recording out = in;
  for (int c = 0; c < in.channel_count; ++c) {
    const int64_t shift = static_cast<int64_t>(c * 1.3 * in.sample_rate_hz) % in.frames;
    const float* src = in.channel(c);
    float* dst = out.samples.data() + c * in.frames;
    for (int64_t n = 0; n < in.frames; ++n) dst[(n + shift) % in.frames] = src[n];
  }
  return out;
}

// The recording's shape, every channel independent white noise (seeded).
Recording WhiteNoise(const Recording& in) {
  Recording out = in;
  std::mt19937 rng(20261204);
  std::normal_distribution<float> normal(0.0f, 0.01f);
  for (float& x : out.samples) x = normal(rng);
  return out;
}

// The session `localizer-cli track --array hydrophones_config_07-HI.csv` runs (the array
// file's sensors, sound speed, reference and water column), with `base`'s choices.
engine::AudioSessionConfig ConfigFor(engine::AudioSessionConfig base) {
  const Xav& xav = LoadXav();
  base.frame_samples = kFrame;
  base.hop_samples = kHop;
  base.seed = 1;
  return TrackConfigFor(base, xav.array.array, ArrayOverrides{}, xav.recording.sample_rate_hz);
}

std::vector<engine::Estimate> Track(const engine::AudioSessionConfig& config, const Recording& rec) {
  auto session = engine::Session::Create(config);
  EXPECT_TRUE(session.ok()) << session.status().ToString();
  std::vector<engine::Estimate> out;
  if (!session.ok()) return out;
  const int64_t block = static_cast<int64_t>(0.25 * rec.sample_rate_hz);
  std::vector<float> buffer;
  uint64_t sequence = 0;
  for (int64_t start = 0; start < rec.frames; start += block) {
    const int64_t n = std::min(block, rec.frames - start);
    buffer.resize(static_cast<size_t>(n * rec.channel_count));
    for (int c = 0; c < rec.channel_count; ++c) {
      std::copy_n(rec.channel(c) + start, n, buffer.begin() + c * n);
    }
    engine::BlockView view{++sequence, rec.channel_count, n, buffer.data()};
    const Status status = (*session)->Process(view, &out);
    EXPECT_TRUE(status.ok()) << status.ToString();
  }
  return out;
}

// Per frame (the session's framing), the 50-1000 Hz energy of one channel (Hann window,
// direct DFT over the band's bins) over its running median: the independent call detector.
std::vector<double> EnergyRatio(const Recording& rec, int channel, size_t frames) {
  const double fs = rec.sample_rate_hz;
  const int k_lo = static_cast<int>(std::ceil(50.0 * kFrame / fs));
  const int k_hi = static_cast<int>(std::floor(1000.0 * kFrame / fs));
  std::vector<double> window(kFrame), cos_t(kFrame), sin_t(kFrame);
  for (int n = 0; n < kFrame; ++n) {
    window[n] = 0.5 - 0.5 * std::cos(2.0 * M_PI * n / (kFrame - 1));
    cos_t[n] = std::cos(2.0 * M_PI * n / kFrame);
    sin_t[n] = std::sin(2.0 * M_PI * n / kFrame);
  }
  std::vector<double> energy(frames, 0.0), x(kFrame);
  for (size_t i = 0; i < frames; ++i) {
    const float* s = rec.channel(channel) + i * kHop;
    for (int n = 0; n < kFrame; ++n) x[n] = window[n] * s[n];
    for (int k = k_lo; k <= k_hi; ++k) {
      double re = 0.0, im = 0.0;
      for (int n = 0, idx = 0; n < kFrame; ++n, idx = (idx + k) & (kFrame - 1)) {
        re += x[n] * cos_t[idx];
        im -= x[n] * sin_t[idx];
      }
      energy[i] += re * re + im * im;
    }
  }
  const int half = static_cast<int>(std::lround(kMedianHalfWindowS * fs / kHop));
  std::vector<double> ratio(frames);
  for (size_t i = 0; i < frames; ++i) {
    const size_t lo = i >= static_cast<size_t>(half) ? i - half : 0;
    const size_t hi = std::min(frames, i + half + 1);
    std::vector<double> w(energy.begin() + lo, energy.begin() + hi);
    std::sort(w.begin(), w.end());
    const double med = w.size() % 2 ? w[w.size() / 2] : 0.5 * (w[w.size() / 2 - 1] + w[w.size() / 2]);
    ratio[i] = energy[i] / med;
  }
  return ratio;
}

struct Counts {
  int frames = 0, present = 0, present_outside = 0, calls = 0, calls_heard = 0;
  bool finite = true;
};

// check_bounds: a present estimate outside config's bounds is a failure (else only counted).
Counts Measure(const std::vector<engine::Estimate>& estimates, const engine::AudioSessionConfig& config,
               const std::vector<double>* ratio, bool check_bounds = true) {
  Counts c;
  c.frames = static_cast<int>(estimates.size());
  for (size_t i = 0; i < estimates.size(); ++i) {
    const engine::Estimate& e = estimates[i];
    c.finite = c.finite && std::isfinite(e.t_s) && e.state.allFinite() && e.covariance.allFinite() &&
               std::isfinite(e.presence_statistic) && std::isfinite(e.presence_threshold);
    if (e.source_present) {
      ++c.present;
      const engine::Vec3 p = e.state.head<3>();
      const bool inside =
          (p.array() >= config.bounds_min_m.array()).all() && (p.array() <= config.bounds_max_m.array()).all();
      if (!inside) {
        ++c.present_outside;
        if (check_bounds) {
          ADD_FAILURE() << "present frame " << i << " at t = " << e.t_s << " s outside the bounds: (" << p.x() << ", "
                        << p.y() << ", " << p.z() << ")";
        }
      }
    }
    if (ratio != nullptr && (*ratio)[i] > kCallRatio) {
      ++c.calls;
      c.calls_heard += e.source_present ? 1 : 0;
    }
  }
  return c;
}

void ExpectContractOnTheRecording(const engine::AudioSessionConfig& base, const char* name, bool check_bounds) {
  const Xav& xav = LoadXav();
  ASSERT_EQ(xav.recording.channel_count, 6);
  const engine::AudioSessionConfig config = ConfigFor(base);
  ASSERT_NEAR(config.bounds_max_m.z(), 7.03, 0.005);        // the surface, from deployment_info.csv
  ASSERT_NEAR(config.bounds_min_m.z(), 7.03 - 8.0, 0.005);  // 8 m of water below it
  const auto estimates = Track(config, xav.recording);
  const int64_t expected = (xav.recording.frames - kFrame) / kHop + 1;
  ASSERT_EQ(static_cast<int64_t>(estimates.size()), expected);
  const std::vector<double> ratio = EnergyRatio(xav.recording, kDetectorChannel, estimates.size());
  const Counts c = Measure(estimates, config, &ratio, check_bounds);
  std::printf("XAV %s: %d frames, %d present, %d present outside the bounds, calls heard %d/%d\n", name, c.frames,
              c.present, c.present_outside, c.calls_heard, c.calls);
  EXPECT_TRUE(c.finite);
  EXPECT_GT(c.present, 0);
  if (check_bounds) {
    EXPECT_EQ(c.present_outside, 0);
  }
  ASSERT_GE(c.calls, 20) << "the detector should find the recording's loud calls (25 measured)";
  EXPECT_GE(c.calls_heard, kMinCallsHeard * c.calls);
}

engine::AudioSessionConfig Band50To1000() {
  engine::AudioSessionConfig base;
  base.band_low_hz = 50.0;  // the authors' fish-sound band
  base.band_high_hz = 1000.0;
  return base;
}

engine::AudioSessionConfig PhatCoherence() {
  engine::AudioSessionConfig base;
  base.weighting = engine::Weighting::kPhatCoherence;
  return base;
}

TEST(XavPresence, PhatWholeBandHearsTheCallsWithinTheWaterColumn) {
  ExpectContractOnTheRecording(engine::AudioSessionConfig{}, "phat", /*check_bounds=*/true);
}

TEST(XavPresence, PhatCoherenceHearsTheCallsWithinTheWaterColumn) {
  ExpectContractOnTheRecording(PhatCoherence(), "phat-coherence", /*check_bounds=*/true);
}

TEST(XavPresence, PhatBand50To1000HearsTheCalls) {
  ExpectContractOnTheRecording(Band50To1000(), "phat 50-1000 Hz", /*check_bounds=*/false);
}

// Known failure: frames 25-35 (t = 1.66-2.30 s) are present at z = -1.12 ... -2.79 m, below
// the bottom (-0.97 m): the cloud, collapsed to sz ~ 1 cm at vz = -2.6 m/s, is predicted
// out of the column as a whole; ParticleSet::ApplyBounds gives every particle the same
// -1e30 log weight, NormaliseWeights makes them equal again, and the track coasts on below
// the bottom until it is dropped.
TEST(XavPresence, PhatBand50To1000PresentEstimatesStayInTheWaterColumn) {
  ExpectContractOnTheRecording(Band50To1000(), "phat 50-1000 Hz", /*check_bounds=*/true);
}

void ExpectNoSourceOn(const Recording& recording, const engine::AudioSessionConfig& base, const char* what,
                      const char* name) {
  const engine::AudioSessionConfig config = ConfigFor(base);
  const auto estimates = Track(config, recording);
  const Counts c = Measure(estimates, config, nullptr);
  std::vector<double> statistic;
  for (const engine::Estimate& e : estimates) statistic.push_back(e.presence_statistic / e.presence_threshold);
  std::sort(statistic.begin(), statistic.end());
  const double median = statistic.empty() ? 0.0 : statistic[statistic.size() / 2];
  std::printf("XAV %s, %s: %d frames, %d present, median statistic / threshold %.2f\n", what, name, c.frames, c.present,
              median);
  EXPECT_TRUE(c.finite);
  // 1e-3 per frame: 0.26 expected in 264 frames; 3 or more has probability < 3e-3.
  EXPECT_LE(c.present, 2);
}

void ExpectNoSourceOnShiftedChannels(const engine::AudioSessionConfig& base, const char* name) {
  const Xav& xav = LoadXav();
  ASSERT_EQ(xav.recording.channel_count, 6);
  ExpectNoSourceOn(Shifted(xav.recording), base, "shifted channels", name);
}

TEST(XavPresence, ShiftedChannelsHoldNoSourcePhat) {
  ExpectNoSourceOnShiftedChannels(engine::AudioSessionConfig{}, "phat");
  ExpectNoSourceOnShiftedChannels(Band50To1000(), "phat 50-1000 Hz");
}

TEST(XavPresence, WhiteNoiseHoldsNoSource) {
  const Xav& xav = LoadXav();
  ASSERT_EQ(xav.recording.channel_count, 6);
  const Recording noise = WhiteNoise(xav.recording);
  ExpectNoSourceOn(noise, engine::AudioSessionConfig{}, "white noise", "phat");
  ExpectNoSourceOn(noise, PhatCoherence(), "white noise", "phat-coherence");
}

}  // namespace
}  // namespace localizer::io
