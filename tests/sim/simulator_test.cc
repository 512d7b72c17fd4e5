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
using testing::Clicks;
using testing::CrossCorrelation;
using testing::kFs;
using testing::kSoundSpeed;
using testing::MeanPower;
using testing::MustSimulate;
using testing::Stationary;
using testing::Tetrahedron;

// Fits A g(t - tau) to a channel by the continuous matched filter
//     C(tau) = sum_n y[n] g(n / fs - tau),
// maximised on a 0.01-sample grid within +-2 samples of the guess and refined by a parabola
// through the best three grid points. For g band-limited below fs / 2 the sampled sum equals
// the continuous correlation (Parseval), so the fit is unbiased; the test below checks it.
struct PulseFit {
  double time_s;
  double amplitude;
};
PulseFit FitPulse(const std::vector<double>& y, const ClickPulse& g, double guess_s) {
  const auto correlate = [&](double tau_s, bool energy) {
    const double half_s = 0.5 * g.duration_s();
    const auto lo = std::max<int64_t>(0, static_cast<int64_t>(std::ceil((tau_s - half_s) * kFs)));
    const auto hi =
        std::min<int64_t>(static_cast<int64_t>(y.size()) - 1, static_cast<int64_t>(std::floor((tau_s + half_s) * kFs)));
    double sum = 0.0;
    for (int64_t n = lo; n <= hi; ++n) {
      const double template_value = g(static_cast<double>(n) / kFs - tau_s);
      sum += (energy ? template_value : y[n]) * template_value;
    }
    return sum;
  };
  const double step_s = 0.01 / kFs;
  int best = 0;
  double best_value = -std::numeric_limits<double>::infinity();
  for (int i = -200; i <= 200; ++i) {
    const double value = correlate(guess_s + i * step_s, false);
    if (value > best_value) best_value = value, best = i;
  }
  const double left = correlate(guess_s + (best - 1) * step_s, false);
  const double right = correlate(guess_s + (best + 1) * step_s, false);
  const double offset = 0.5 * (left - right) / (left - 2.0 * best_value + right);
  const double time_s = guess_s + (best + offset) * step_s;
  return {time_s, correlate(time_s, false) / correlate(time_s, true)};
}

// Each click's arrival at each sensor against te + |p(te) - m_k| / c, in samples; returns the
// largest error and checks the amplitude against 1 / range.
double WorstClickArrivalError(const ArrayGeometry& array, const SimOptions& o) {
  const SimResult r = MustSimulate(array, o);
  const ClickPulse g(o.band_low_hz, o.band_high_hz);
  double worst = 0.0;
  int fitted = 0;
  for (double te_s : ClickEmissionTimes(o, -1.0, o.duration_s)) {
    const Vec3 p = o.trajectory.PositionAt(te_s);
    for (int k = 0; k < array.sensor_count(); ++k) {
      const double range_m = (p - array.sensor_m(k)).norm();
      const double arrival_s = te_s + range_m / array.sound_speed_mps();
      if (arrival_s - g.duration_s() < 0.0 || arrival_s + g.duration_s() > o.duration_s) continue;
      const PulseFit fit = FitPulse(Channel(r, k), g, arrival_s);
      worst = std::max(worst, std::abs(fit.time_s - arrival_s) * kFs);
      EXPECT_NEAR(fit.amplitude * range_m, 1.0, 1e-3) << "click at " << te_s << " sensor " << k;
      ++fitted;
    }
  }
  EXPECT_GT(fitted, 20 * array.sensor_count() * o.duration_s * 0.8);
  return worst;
}

TEST(Simulator, MatchedFilterFitIsUnbiasedOnASampledPulse) {
  const ClickPulse g(300.0, 3000.0);
  for (double true_s : {0.0200, 0.02003, 0.020071}) {
    std::vector<double> y(600, 0.0);
    for (int n = 0; n < 600; ++n) y[n] = 0.25 * g(n / kFs - true_s);
    const PulseFit fit = FitPulse(y, g, true_s + 0.7 / kFs);
    EXPECT_NEAR((fit.time_s - true_s) * kFs, 0.0, 1e-3);
    EXPECT_NEAR(fit.amplitude, 0.25, 1e-4);
  }
}

TEST(Simulator, KnownGeometryGivesKnownDelays) {
  // Stationary broadband source, noiseless: the sample-level cross-correlation of each pair
  // peaks at the integer lag nearest the true TDOA.
  const ArrayGeometry array = Tetrahedron();
  const Vec3 source_m(6.0, 3.0, -7.0);
  const SimResult r = MustSimulate(array, Stationary(source_m));
  const std::vector<double> reference = Channel(r, 0);
  const Eigen::VectorXd tdoa_s = array.Tdoa(source_m);
  for (int p = 0; p < array.pair_count(); ++p) {
    const double true_lag = tdoa_s(p) * kFs;
    // A true lag near a half-integer could round either way; this geometry avoids it.
    ASSERT_LT(std::abs(true_lag - std::round(true_lag)), 0.4) << "pair " << p;
    const std::vector<double> other = Channel(r, array.sensor_of_pair(p));
    const int max_lag = static_cast<int>(std::ceil(array.max_delay_s(p) * kFs)) + 3;
    int best_lag = 0;
    double best = -std::numeric_limits<double>::infinity();
    for (int lag = -max_lag; lag <= max_lag; ++lag) {
      const double value = CrossCorrelation(other, reference, lag);
      if (value > best) best = value, best_lag = lag;
    }
    EXPECT_EQ(best_lag, std::lround(true_lag)) << "pair " << p << " true lag " << true_lag;
  }
}

TEST(Simulator, ClickArrivalsMatchRangeOverSoundSpeed) {
  const ArrayGeometry array = Tetrahedron();
  const double worst = WorstClickArrivalError(array, Clicks(Vec3(6.0, 3.0, -7.0)));
  std::printf("stationary clicks: worst arrival-time error %.2e samples\n", worst);
  EXPECT_LT(worst, 0.1);
}

TEST(Simulator, MovingClickSourceArrivesFromWhereItWasAtEmission) {
  // A turning source at 2 m/s: each click reaches sensor k at te + |p(te) - m_k| / c, with
  // p at the emission instant (not at reception), and amplitude 1 / |p(te) - m_k|.
  const ArrayGeometry array = Tetrahedron();
  SimOptions o = Clicks(Vec3(8.0, -3.0, -6.0));
  o.duration_s = 2.0;
  o.trajectory.velocity_mps = Vec3(-1.2, 1.6, 0.05);
  o.trajectory.turn_rate_radps = 0.3;
  const double worst = WorstClickArrivalError(array, o);
  std::printf("moving clicks: worst arrival-time error %.2e samples\n", worst);
  EXPECT_LT(worst, 0.1);
}

TEST(Simulator, AmplitudeFollowsInverseRange) {
  const ArrayGeometry array = Tetrahedron();
  const Vec3 source_m(2.5, 0.5, -9.0);  // near the array: ranges from 1.9 to 3.8 m
  const SimResult r = MustSimulate(array, Stationary(source_m));
  const double rms_ref = std::sqrt(MeanPower(Channel(r, 0)));
  const double range_ref = (source_m - array.sensor_m(0)).norm();
  double worst = 0.0;
  for (int k = 1; k < array.sensor_count(); ++k) {
    const double range_m = (source_m - array.sensor_m(k)).norm();
    const double ratio = std::sqrt(MeanPower(Channel(r, k))) / rms_ref;
    EXPECT_NEAR(ratio / (range_ref / range_m), 1.0, 0.02) << "sensor " << k;
    worst = std::max(worst, std::abs(ratio / (range_ref / range_m) - 1.0));
  }
  std::printf("RMS ratio against inverse range ratio: worst relative error %.2e\n", worst);
}

TEST(Simulator, SpreadingIsClampedAtOneMetre) {
  const ArrayGeometry array = Tetrahedron();
  const Vec3 source_m = array.sensor_m(0) + Vec3(0.3, 0.2, 0.1);  // 0.37 m from sensor 0
  const SimResult r = MustSimulate(array, Stationary(source_m));
  const double rms0 = std::sqrt(MeanPower(Channel(r, 0)));
  EXPECT_NEAR(rms0, 1.0, 0.03);  // unit-RMS source at gain 1
  for (int k = 1; k < array.sensor_count(); ++k) {
    const double range_m = (source_m - array.sensor_m(k)).norm();
    EXPECT_NEAR(std::sqrt(MeanPower(Channel(r, k))) / rms0 * range_m, 1.0, 0.02) << k;
  }
}

// te from te + |p(te) - m| / c = t by bisection: independent of the simulator's iteration.
double EmissionTimeByBisection(const Trajectory& t, const Vec3& m, double reception_s) {
  double lo = reception_s - 10.0;
  double hi = reception_s;
  for (int i = 0; i < 200 && hi - lo > 1e-14; ++i) {
    const double mid = 0.5 * (lo + hi);
    (mid + (t.PositionAt(mid) - m).norm() / kSoundSpeed > reception_s ? hi : lo) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(Simulator, TruthIsTheSourceStateAtTheEmissionHeardByTheReference) {
  const ArrayGeometry array = Tetrahedron(/*reference_sensor=*/2);
  SimOptions o = Stationary(Vec3(12.0, -5.0, -4.0));
  o.duration_s = 3.0;
  o.truth_step_s = 0.01;
  o.trajectory.velocity_mps = Vec3(-1.5, 1.0, 0.1);
  o.trajectory.turn_rate_radps = 0.25;
  const SimResult r = MustSimulate(array, o);
  ASSERT_EQ(r.truth.size(), 301u);
  const Vec3& m_ref = array.sensor_m(2);
  std::vector<double> te(r.truth.size());
  for (size_t i = 0; i < r.truth.size(); ++i) {
    const TruthRow& row = r.truth[i];
    EXPECT_NEAR(row.t_s, static_cast<double>(i) * 0.01, 1e-12);
    te[i] = EmissionTimeByBisection(o.trajectory, m_ref, row.t_s);
    EXPECT_NEAR(te[i] + (row.position_m - m_ref).norm() / kSoundSpeed, row.t_s, 1e-12);
    EXPECT_LT((row.position_m - o.trajectory.PositionAt(te[i])).norm(), 1e-9) << row.t_s;
  }
  // Velocity against central differences of the truth positions over emission time (over
  // reception time they would carry the Doppler factor dte/dt = 1 / (1 + dr/dt / c)).
  for (size_t i = 1; i + 1 < r.truth.size(); ++i) {
    const Vec3 difference = (r.truth[i + 1].position_m - r.truth[i - 1].position_m) / (te[i + 1] - te[i - 1]);
    EXPECT_LT((difference - r.truth[i].velocity_mps).norm(), 1e-5) << r.truth[i].t_s;
  }
}

TEST(Simulator, TruthAtInterpolatesAndClamps) {
  const ArrayGeometry array = Tetrahedron();
  SimOptions o = Stationary(Vec3(12.0, -5.0, -4.0));
  o.trajectory.velocity_mps = Vec3(-1.5, 1.0, 0.0);
  o.truth_step_s = 0.1;
  const SimResult r = MustSimulate(array, o);
  const TruthRow mid = r.TruthAt(0.45);
  EXPECT_DOUBLE_EQ(mid.t_s, 0.45);
  EXPECT_LT((mid.position_m - 0.5 * (r.truth[4].position_m + r.truth[5].position_m)).norm(), 1e-12);
  EXPECT_EQ(r.TruthAt(-1.0).position_m, r.truth.front().position_m);
  EXPECT_EQ(r.TruthAt(99.0).position_m, r.truth.back().position_m);
}

}  // namespace
}  // namespace localizer::engine
