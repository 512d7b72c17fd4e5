// Diffuse weighting (pair_spectra.h): a room's reverberation is close to a diffuse field,
// coherent across a small array's pairs at low frequencies with zero phase. Unweighted, PHAT
// reads it as a source at lag 0 on every pair: a 4-microphone board's normal. Weighted by
// 1 - sinc^2 per pair, the field scores far less, and a source beside it is found more often.
// The field: 256 independent white plane waves from a Fibonacci lattice on the sphere.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "engine/doa/pair_spectra.h"
#include "engine/doa/srp_phat.h"
#include "tests/doa/plane_wave.h"

namespace localizer::engine {
namespace {

using testing::AngleBetween;
using testing::FromAzimuthElevation;
using testing::PlaneSource;
using testing::PlaneWaveFrame;
using testing::PlaneWaveScene;
using testing::Respeaker4;

// `count` plane waves over the sphere (Fibonacci lattice), `total_power` per bin in all.
std::vector<PlaneSource> DiffuseField(int count, double total_power) {
  std::vector<PlaneSource> field;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / count;
    const double r = std::sqrt(1.0 - z * z);
    field.push_back({Vec3(r * std::cos(golden * i), r * std::sin(golden * i), z), total_power / count});
  }
  return field;
}

struct Tally {
  int frames_with_peak = 0;
  int on_source = 0;                  // a peak within 10 degrees of the source
  std::vector<double> strongest_z;    // per frame, the strongest peak's statistic (0: none)
  std::vector<double> elevation_rad;  // per frame with a peak, the strongest one's
  double threshold = 0.0;
};

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

Tally Frames(bool weighted, bool with_source, int frames) {
  PlaneWaveScene scene;
  scene.sensors_m = Respeaker4();
  scene.noise_power = 0.01;
  SrpOptions options;
  options.sample_rate_hz = scene.sample_rate_hz;
  options.frame_samples = scene.frame_samples;
  options.band_low_hz = scene.band_low_hz;
  options.band_high_hz = scene.band_high_hz;
  options.source_side = Vec3::UnitZ();
  options.diffuse_weighting = weighted;
  auto srp = SrpPhat::Create(scene.sensors_m, options);
  EXPECT_TRUE(srp.ok()) << srp.status().ToString();
  Tally tally;
  if (!srp.ok()) return tally;
  tally.threshold = srp->threshold();
  const Vec3 source = FromAzimuthElevation(1.0, 0.2);  // a talker a little above the board's plane
  std::vector<PlaneSource> sources;
  if (with_source) sources.push_back({source, 1.0});  // direct to diffuse 0 dB
  for (const PlaneSource& s : DiffuseField(256, 1.0)) sources.push_back(s);
  for (int i = 0; i < frames; ++i) {
    const std::vector<float> frame = PlaneWaveFrame(scene, sources, 500 + static_cast<uint64_t>(i));
    auto peaks = srp->Analyse(frame.data());
    EXPECT_TRUE(peaks.ok());
    if (!peaks.ok() || peaks->empty()) {
      tally.strongest_z.push_back(0.0);
      continue;
    }
    ++tally.frames_with_peak;
    tally.strongest_z.push_back(peaks->front().statistic);
    tally.elevation_rad.push_back(peaks->front().elevation_rad);
    for (const DirectionPeak& p : *peaks) {
      if (AngleBetween(p.direction, source) < 10.0 * std::numbers::pi / 180.0) {
        ++tally.on_source;
        break;
      }
    }
  }
  return tally;
}

// In one frame a diffuse field is a random superposition: its strongest SRP peak lies at a
// random azimuth, lifted towards the normal (the low bins' lag-0 pull), far above the
// threshold set for independent noise. Weighted, the bins that carry that pull count little:
// the field's statistic falls to near the threshold.
TEST(DiffuseWeighting, ADiffuseFieldScoresFarLessWeighted) {
  constexpr int kFrames = 30;
  const Tally plain = Frames(false, false, kFrames);
  const Tally weighted = Frames(true, false, kFrames);
  std::printf(
      "diffuse field alone, %d frames (threshold %.2f): median strongest statistic unweighted %.2f "
      "(median elevation %.2f rad), weighted %.2f (%.2f rad)\n",
      kFrames, plain.threshold, Median(plain.strongest_z), Median(plain.elevation_rad), Median(weighted.strongest_z),
      Median(weighted.elevation_rad));
  EXPECT_GE(Median(plain.strongest_z), 2.0 * plain.threshold);
  EXPECT_LE(Median(weighted.strongest_z), 0.5 * Median(plain.strongest_z));
  EXPECT_LT(Median(weighted.elevation_rad), Median(plain.elevation_rad));
}

TEST(DiffuseWeighting, ASourceBesideADiffuseFieldIsFoundMoreOftenWeighted) {
  constexpr int kFrames = 30;
  const Tally plain = Frames(false, true, kFrames);
  const Tally weighted = Frames(true, true, kFrames);
  std::printf("source at 0 dB to the diffuse field, %d frames: a peak within 10 degrees unweighted %d, weighted %d\n",
              kFrames, plain.on_source, weighted.on_source);
  EXPECT_GE(weighted.on_source, kFrames * 9 / 10);
  EXPECT_GT(weighted.on_source, plain.on_source);
}

TEST(DiffuseWeighting, RefusesADistancePerPairThatDoesNotFit) {
  PairSpectraOptions o;
  o.sensors = 4;
  o.frame_samples = 512;
  o.sample_rate_hz = 16000.0;
  o.max_lag_samples = 8;
  o.diffuse_distance_m = {0.05, 0.05};  // 6 pairs
  EXPECT_FALSE(PairSpectra::Create(o).ok());
  o.diffuse_distance_m.assign(6, 0.0);
  EXPECT_FALSE(PairSpectra::Create(o).ok());
  o.diffuse_distance_m.assign(6, 0.05);
  EXPECT_TRUE(PairSpectra::Create(o).ok());
}

}  // namespace
}  // namespace localizer::engine
