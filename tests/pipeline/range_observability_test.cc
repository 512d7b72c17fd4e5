// Range observability (engine/pipeline/range_observability.h): the frame's range bound is the
// spread that multilateration of noisy TDOAs actually shows, it grows as the range squared,
// and a session says far field for a distant source and not for a near one.
#include "engine/pipeline/range_observability.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "engine/array/multilateration.h"
#include "engine/pipeline/session.h"
#include "engine/sim/simulator.h"

namespace localizer::engine {
namespace {

constexpr double kC = 1500.0;
constexpr double kSigmaS = 2e-6;

// A regular tetrahedron with 2 m edges about the origin.
ArrayGeometry Tetrahedron(double edge_m, double c) {
  const double a = edge_m / (2.0 * std::sqrt(2.0));
  return *ArrayGeometry::Create({Vec3(a, a, a), Vec3(a, -a, -a), Vec3(-a, a, -a), Vec3(-a, -a, a)}, c);
}

Eigen::VectorXd Sigmas(const ArrayGeometry& array, double sigma_s) {
  return Eigen::VectorXd::Constant(array.pair_count(), sigma_s);
}

TEST(RangeObservability, TheBoundIsTheSpreadOfFixesFromNoisyTdoas) {
  const ArrayGeometry array = Tetrahedron(2.0, kC);
  const Vec3 source(3.0, 2.0, -1.0);  // 3.7 m: under 2 apertures
  const RangeObservability judged = JudgeRange(array, source, Sigmas(array, kSigmaS));
  ASSERT_GT(judged.range_sd_m, 0.0);
  EXPECT_FALSE(judged.far_field);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, kSigmaS);
  double sum = 0.0, sum_sq = 0.0;
  int fixes = 0;
  for (int i = 0; i < 400; ++i) {
    Eigen::VectorXd tdoa = array.Tdoa(source);
    for (Eigen::Index p = 0; p < tdoa.size(); ++p) tdoa(p) += noise(rng);
    auto fix = Multilaterate(array, tdoa);
    if (!fix.ok()) continue;
    const double range = (fix->position_m - array.centroid_m()).norm();
    sum += range;
    sum_sq += range * range;
    ++fixes;
  }
  ASSERT_GT(fixes, 380);
  const double sd = std::sqrt(sum_sq / fixes - (sum / fixes) * (sum / fixes));
  EXPECT_NEAR(sd / judged.range_sd_m, 1.0, 0.15) << "fixes' range sd " << sd << " m, bound " << judged.range_sd_m;
}

TEST(RangeObservability, GrowsAsTheRangeSquaredAndADistantSourceIsFarField) {
  const ArrayGeometry array = Tetrahedron(2.0, kC);
  const Vec3 u = Vec3(0.6, -0.48, 0.64).normalized();
  auto at = [&](double r) { return JudgeRange(array, r * u, Sigmas(array, kSigmaS)); };
  // Beyond a few apertures the TDOAs fix 1/r: sd(r) = r^2 sd(1/r).
  EXPECT_NEAR(at(40.0).range_sd_m / at(20.0).range_sd_m, 4.0, 0.4);
  EXPECT_FALSE(at(4.0).far_field);
  const RangeObservability far = at(200.0);
  EXPECT_TRUE(far.far_field) << "range sd " << far.range_sd_m << " m at 200 m";
  EXPECT_NEAR(far.range_m, 200.0, 1e-9);
}

TEST(RangeObservability, PairsWithoutASigmaAreLeftOut) {
  const ArrayGeometry array = Tetrahedron(2.0, kC);
  const Vec3 source(6.0, -3.0, 2.0);
  Eigen::VectorXd sigma_s = Sigmas(array, kSigmaS);
  EXPECT_GT(JudgeRange(array, source, sigma_s).range_sd_m, 0.0);
  // A 4-sensor array with a pair that heard nothing cannot bound a position: not computed.
  sigma_s(1) = 0.0;
  const RangeObservability blind = JudgeRange(array, source, sigma_s);
  EXPECT_EQ(blind.range_sd_m, 0.0);
  EXPECT_FALSE(blind.far_field);
}

TEST(PairSigmaHistory, IsTheMedianOfTheFramesWithAPeakAndFallsBack) {
  PairSigmaHistory history;
  Measurement m;
  m.pairs.resize(2);
  const double first[] = {1e-6, 9e-6, 2e-6, 3e-6, 100e-6};  // pair 0's sigmas over 5 frames
  for (double sigma : first) {
    m.pairs[0].peak_value = 1.0;
    m.pairs[0].delay_sigma_s = sigma;
    m.pairs[1].peak_value = 0.0;  // never a peak
    history.Add(m, 50e-6);
  }
  Eigen::VectorXd median = history.Median();
  ASSERT_EQ(median.size(), 2);
  EXPECT_DOUBLE_EQ(median(0), 3e-6);
  EXPECT_EQ(median(1), 0.0);
  // A peak without its own sigma takes the fallback; the window keeps the last 8 frames.
  for (int i = 0; i < PairSigmaHistory::kFrames; ++i) {
    m.pairs[0].delay_sigma_s = 0.0;
    history.Add(m, 7e-6);
  }
  EXPECT_DOUBLE_EQ(history.Median()(0), 7e-6);
}

// A 0.4 m tetrahedron in air, a 300-4000 Hz source at 10 dB: a talker 0.8 m away (2
// apertures) is in the near field; one 20 m away (50 apertures; the frame's range sd is
// about 20 m there) is not, and the session says so frame by frame once its track is out
// there. The search volume is widened to hold it (the default is 10 apertures); the track
// starts from both exact solutions (one near the array) and settles on the far one within
// the first second, from which the far source is judged.
TEST(RangeObservability, ASessionSaysFarFieldForADistantSourceOnly) {
  const ArrayGeometry array = Tetrahedron(0.4, 343.0);
  std::vector<Vec3> sensors;
  for (int s = 0; s < array.sensor_count(); ++s) sensors.push_back(array.sensor_m(s));
  for (const double range_m : {0.8, 20.0}) {
    SimOptions o;
    o.sample_rate_hz = 16000.0;
    o.band_low_hz = 300.0;
    o.band_high_hz = 4000.0;
    o.duration_s = 6.0;
    o.trajectory.position_m = range_m * Vec3(0.6, 0.64, 0.48).normalized();
    o.trajectory.velocity_mps = Vec3::Zero();
    o.snr_db = 10.0;
    o.seed = 5;
    const SimResult sim = *Simulate(array, o);
    AudioSessionConfig config;
    config.sensors_m = sensors;
    config.sound_speed_mps = 343.0;
    config.sample_rate_hz = o.sample_rate_hz;
    config.search_radius_m = 40.0;
    config.seed = 3;
    auto session = std::move(*Session::Create(config));
    std::vector<Estimate> estimates;
    ASSERT_TRUE(session->Process({1, sim.channel_count, sim.samples_per_channel, sim.samples.data()}, &estimates).ok());
    int initialised = 0, far = 0;
    for (const Estimate& e : estimates) {
      if (!e.initialised || (range_m > 1.0 && e.t_s < 1.0)) continue;
      ++initialised;
      far += e.far_field;
      EXPECT_GT(e.range_sd_m, 0.0);
    }
    ASSERT_GT(initialised, 30) << range_m << " m";
    if (range_m < 1.0) {
      EXPECT_EQ(far, 0) << "a source at 2 apertures";
    } else {
      EXPECT_GE(far, initialised * 9 / 10) << "a source at 50 apertures";
    }
  }
}

}  // namespace
}  // namespace localizer::engine
