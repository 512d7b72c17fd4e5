// The simulator's noise, echoes and impulses (engine/sim/simulator.h).
#include "engine/sim/simulator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "engine/sim/propagation.h"
#include "engine/sim/source_signal.h"
#include "tests/sim/simulator_fixture.h"

namespace localizer::engine {
namespace {

using testing::Channel;
using testing::CrossCorrelation;
using testing::kFs;
using testing::kSoundSpeed;
using testing::MeanPower;
using testing::MustSimulate;
using testing::Stationary;
using testing::Tetrahedron;

// Noise power against the direct-path signal power of each channel, in dB.
std::vector<double> MeasuredSnrDb(const ArrayGeometry& array, SimOptions o) {
  const double snr_db = o.snr_db;
  const SimResult noisy = MustSimulate(array, o);
  o.snr_db = std::numeric_limits<double>::infinity();
  const SimResult clean = MustSimulate(array, o);
  o.surface_reflection_enabled = false;
  const SimResult direct = MustSimulate(array, o);
  std::vector<double> measured;
  for (int k = 0; k < array.sensor_count(); ++k) {
    std::vector<double> noise = Channel(noisy, k);
    const std::vector<double> signal = Channel(clean, k);
    for (size_t n = 0; n < noise.size(); ++n) noise[n] -= signal[n];
    measured.push_back(10.0 * std::log10(MeanPower(Channel(direct, k)) / MeanPower(noise)));
    EXPECT_NEAR(measured.back(), snr_db, 0.3) << "sensor " << k;
  }
  return measured;
}

TEST(Simulator, NoiseIsAtTheRequestedSnrPerChannel) {
  const ArrayGeometry array = Tetrahedron();
  SimOptions o = Stationary(Vec3(2.5, 0.5, -9.0));  // unequal channel powers
  o.duration_s = 2.0;
  for (double snr_db : {20.0, 5.0, -3.0}) {
    o.snr_db = snr_db;
    double worst_db = 0.0;
    for (double measured_db : MeasuredSnrDb(array, o)) {
      worst_db = std::max(worst_db, std::abs(measured_db - snr_db));
    }
    std::printf("SNR %g dB: worst channel off by %.3f dB\n", snr_db, worst_db);
  }
}

TEST(Simulator, SnrIsRelativeToTheDirectPathWhenThereIsAnEcho) {
  const ArrayGeometry array = Tetrahedron();
  SimOptions o = Stationary(Vec3(10.0, 0.0, -5.0));
  o.duration_s = 2.0;
  o.snr_db = 5.0;
  o.surface_reflection_enabled = true;
  MeasuredSnrDb(array, o);
}

TEST(Simulator, SurfaceEchoIsANegativeCopyAtTheImagePathDifference) {
  const ArrayGeometry array = Tetrahedron();
  SimOptions o = Stationary(Vec3(10.0, 0.0, -5.0));
  o.duration_s = 3.0;
  o.surface_reflection_enabled = true;
  o.surface_reflection = -0.9;
  const SimResult r = MustSimulate(array, o);
  o.surface_reflection_enabled = false;
  const SimResult no_echo = MustSimulate(array, o);
  const Vec3 image_m = MirrorInHorizontalPlane(o.trajectory, 0.0).position_m;
  for (int k = 0; k < array.sensor_count(); ++k) {
    const double direct_m = (o.trajectory.position_m - array.sensor_m(k)).norm();
    const double reflected_m = (image_m - array.sensor_m(k)).norm();
    const double echo_lag = (reflected_m - direct_m) / kSoundSpeed * kFs;  // ~50 samples
    // y = a s(t - t1) + b s(t - t2): the autocorrelation at the echo lag, over that at 0, is
    // a b / (a^2 + b^2) (the source autocorrelation is ~0 that far out).
    const double a = 1.0 / direct_m;
    const double b = -0.9 / reflected_m;
    const std::vector<double> y = Channel(r, k);
    const double zero_lag = CrossCorrelation(y, y, 0);
    int lowest_lag = 0;
    double lowest = std::numeric_limits<double>::infinity();
    for (int lag = 10; lag <= 150; ++lag) {
      const double value = CrossCorrelation(y, y, lag) / zero_lag;
      if (value < lowest) lowest = value, lowest_lag = lag;
    }
    EXPECT_LE(std::abs(lowest_lag - echo_lag), 1.0) << "sensor " << k;
    EXPECT_NEAR(lowest, a * b / (a * a + b * b), 0.05) << "sensor " << k;
    const std::vector<double> plain = Channel(no_echo, k);
    const int lag = static_cast<int>(std::lround(echo_lag));
    EXPECT_LT(std::abs(CrossCorrelation(plain, plain, lag) / CrossCorrelation(plain, plain, 0)), 0.05);
  }
}

// A hard bottom: a positive copy at the image-source delay, on top of the direct path.
TEST(Simulator, BottomEchoIsAPositiveCopyAtTheImagePathDifference) {
  const ArrayGeometry array = Tetrahedron();
  SimOptions o = Stationary(Vec3(10.0, 0.0, -15.0));
  o.duration_s = 3.0;
  o.bottom_reflection_enabled = true;
  o.bottom_z_m = -20.0;
  o.bottom_reflection = 0.5;
  const SimResult r = MustSimulate(array, o);
  const Vec3 image_m = MirrorInHorizontalPlane(o.trajectory, -20.0).position_m;
  for (int k = 0; k < array.sensor_count(); ++k) {
    const double direct_m = (o.trajectory.position_m - array.sensor_m(k)).norm();
    const double reflected_m = (image_m - array.sensor_m(k)).norm();
    const double echo_lag = (reflected_m - direct_m) / kSoundSpeed * kFs;  // 30-70 samples
    const double a = 1.0 / direct_m;
    const double b = 0.5 / reflected_m;
    const std::vector<double> y = Channel(r, k);
    const double zero_lag = CrossCorrelation(y, y, 0);
    int highest_lag = 0;
    double highest = -std::numeric_limits<double>::infinity();
    for (int lag = 10; lag <= 150; ++lag) {
      const double value = CrossCorrelation(y, y, lag) / zero_lag;
      if (value > highest) highest = value, highest_lag = lag;
    }
    EXPECT_LE(std::abs(highest_lag - echo_lag), 1.0) << "sensor " << k;
    EXPECT_NEAR(highest, a * b / (a * a + b * b), 0.05) << "sensor " << k;
  }
}

// Impulses: on ~impulse_probability of the samples of every channel, independently, with a
// scale of impulse_scale_over_noise_std Gaussian noise stds; the Gaussian part is unchanged.
TEST(Simulator, ImpulsesAppearAtTheAskedRateAndScale) {
  const ArrayGeometry array = Tetrahedron();
  SimOptions o = Stationary(Vec3(6.0, 3.0, -7.0));
  o.duration_s = 4.0;
  o.snr_db = 0.0;
  const SimResult gaussian = MustSimulate(array, o);
  o.impulse_probability = 0.01;
  o.impulse_scale_over_noise_std = 30.0;
  o.impulse_alpha = 1.5;
  const SimResult impulsive = MustSimulate(array, o);
  o.snr_db = std::numeric_limits<double>::infinity();
  const SimResult clean = MustSimulate(array, o);
  std::vector<std::vector<bool>> hit(array.sensor_count());
  for (int k = 0; k < array.sensor_count(); ++k) {
    const std::vector<double> g = Channel(gaussian, k), x = Channel(impulsive, k), c = Channel(clean, k);
    double noise_power = 0.0;
    std::vector<double> sizes;
    for (size_t n = 0; n < g.size(); ++n) {
      noise_power += (g[n] - c[n]) * (g[n] - c[n]);
      hit[k].push_back(x[n] != g[n]);
      if (x[n] != g[n]) sizes.push_back(std::abs(x[n] - g[n]));
    }
    const double noise_std = std::sqrt(noise_power / static_cast<double>(g.size()));
    const double n = static_cast<double>(g.size());
    const double expected = 0.01 * n;  // binomial: std ~ sqrt(0.01 n) ~ 21 of ~441
    EXPECT_NEAR(static_cast<double>(sizes.size()), expected, 5.0 * std::sqrt(expected)) << k;
    // |S1(1.5, 0, 1, 0)| has median ~0.97, so the median impulse is ~30 noise stds.
    std::nth_element(sizes.begin(), sizes.begin() + sizes.size() / 2, sizes.end());
    EXPECT_NEAR(sizes[sizes.size() / 2] / noise_std, 30.0, 6.0) << k;
  }
  // Independent per channel: coincidences at the product rate (~4 of 44100), not ~441.
  int both = 0;
  for (size_t n = 0; n < hit[0].size(); ++n) both += hit[0][n] && hit[1][n];
  EXPECT_LT(both, 20);
}

}  // namespace
}  // namespace localizer::engine
