#include "engine/sim/simulator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "engine/sim/propagation.h"
#include "engine/sim/source_signal.h"

namespace localizer::engine {
namespace {

constexpr double kSoundSpeed = 1500.0;
constexpr double kFs = 11025.0;

// A 2 m tetrahedron centred at 10 m depth (the tetra-water array).
ArrayGeometry Tetrahedron(int reference_sensor = 0) {
  const double a = 2.0 / (2.0 * std::sqrt(2.0));
  const Vec3 c(0.0, 0.0, -10.0);
  auto g = ArrayGeometry::Create({c + Vec3(a, a, a), c + Vec3(a, -a, -a), c + Vec3(-a, a, -a), c + Vec3(-a, -a, a)},
                                 kSoundSpeed, reference_sensor);
  EXPECT_TRUE(g.ok()) << g.status().ToString();
  return *g;
}

SimOptions Stationary(const Vec3& source_m) {
  SimOptions o;
  o.sample_rate_hz = kFs;
  o.duration_s = 1.0;
  o.band_low_hz = 300.0;
  o.band_high_hz = 3000.0;
  o.snr_db = std::numeric_limits<double>::infinity();
  o.trajectory.position_m = source_m;
  o.seed = 5;
  return o;
}

SimResult MustSimulate(const ArrayGeometry& array, const SimOptions& o) {
  StatusOr<SimResult> r = Simulate(array, o);
  EXPECT_TRUE(r.ok()) << r.status().ToString();
  return std::move(r).value();
}

std::vector<double> Channel(const SimResult& r, int k) {
  const float* begin = r.samples.data() + k * r.samples_per_channel;
  return std::vector<double>(begin, begin + r.samples_per_channel);
}

double MeanPower(const std::vector<double>& x) {
  double sum = 0.0;
  for (double v : x) sum += v * v;
  return sum / static_cast<double>(x.size());
}

// sum_n a[n + lag] b[n] over the overlap: direct O(n) per lag.
double CrossCorrelation(const std::vector<double>& a, const std::vector<double>& b, int lag) {
  double sum = 0.0;
  const auto size = static_cast<int>(a.size());
  for (int n = std::max(0, -lag); n < std::min(size, size - lag); ++n) sum += a[n + lag] * b[n];
  return sum;
}

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

SimOptions Clicks(const Vec3& source_m) {
  SimOptions o = Stationary(source_m);
  o.signal = SourceSignal::kClicks;
  o.click_rate_hz = 20.0;
  return o;
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

TEST(Simulator, SameSeedSameSamplesOtherSeedOtherSamples) {
  const ArrayGeometry array = Tetrahedron();
  SimOptions o = Stationary(Vec3(6.0, 3.0, -7.0));
  o.snr_db = 10.0;
  o.trajectory.velocity_mps = Vec3(1.0, 0.0, 0.0);
  const SimResult a = MustSimulate(array, o);
  EXPECT_EQ(a.samples, MustSimulate(array, o).samples);
  o.seed += 1;
  const SimResult b = MustSimulate(array, o);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  size_t equal = 0;
  for (size_t n = 0; n < a.samples.size(); ++n) equal += a.samples[n] == b.samples[n];
  EXPECT_LT(equal, a.samples.size() / 1000);
}

TEST(Simulator, OutputShapeAndDefaultsAreValid) {
  EXPECT_TRUE(SimOptions().Validate().ok());
  const ArrayGeometry array = Tetrahedron();
  SimOptions o = Stationary(Vec3(6.0, 3.0, -7.0));
  o.duration_s = 0.5;
  const SimResult r = MustSimulate(array, o);
  EXPECT_EQ(r.channel_count, 4);
  EXPECT_EQ(r.samples_per_channel, 5513);  // round(0.5 * 11025)
  EXPECT_EQ(r.samples.size(), 4u * 5513u);
  EXPECT_EQ(r.sample_rate_hz, kFs);
}

struct BadOption {
  const char* field;
  void (*spoil)(SimOptions&);
};

TEST(Simulator, BadOptionsAreInvalidArgumentsNamingTheField) {
  constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const BadOption cases[] = {
      {"sample_rate_hz", [](SimOptions& o) { o.sample_rate_hz = 0.0; }},
      {"sample_rate_hz", [](SimOptions& o) { o.sample_rate_hz = kNan; }},
      {"duration_s", [](SimOptions& o) { o.duration_s = -1.0; }},
      {"duration_s", [](SimOptions& o) { o.duration_s = kInf; }},
      {"duration_s", [](SimOptions& o) { o.duration_s = 1e6; }},   // 1.1e10 samples
      {"duration_s", [](SimOptions& o) { o.duration_s = 1e-6; }},  // no sample
      {"band_low_hz", [](SimOptions& o) { o.band_low_hz = -5.0; }},
      {"band_high_hz", [](SimOptions& o) { o.band_high_hz = 6000.0; }},
      {"band_low_hz", [](SimOptions& o) { o.band_low_hz = 3000.0; }},
      {"click_rate_hz",
       [](SimOptions& o) {
         o.signal = SourceSignal::kClicks;
         o.click_rate_hz = 0.0;
       }},
      {"snr_db", [](SimOptions& o) { o.snr_db = kNan; }},
      {"surface_reflection", [](SimOptions& o) { o.surface_reflection = -1.5; }},
      {"surface_z_m", [](SimOptions& o) { o.surface_z_m = kInf; }},
      {"bottom_reflection", [](SimOptions& o) { o.bottom_reflection = 1.5; }},
      {"bottom_z_m", [](SimOptions& o) { o.bottom_z_m = kNan; }},
      {"impulse_probability", [](SimOptions& o) { o.impulse_probability = 1.5; }},
      {"impulse_scale_over_noise_std", [](SimOptions& o) { o.impulse_scale_over_noise_std = 0.0; }},
      {"impulse_alpha", [](SimOptions& o) { o.impulse_alpha = 2.5; }},
      {"tone_count",
       [](SimOptions& o) {
         o.signal = SourceSignal::kTonalBroadband;
         o.tone_count = 0;
       }},
      {"tone_power_fraction",
       [](SimOptions& o) {
         o.signal = SourceSignal::kTonalBroadband;
         o.tone_power_fraction = -0.1;
       }},
      {"truth_step_s", [](SimOptions& o) { o.truth_step_s = 0.0; }},
      {"truth_step_s", [](SimOptions& o) { o.truth_step_s = 1e-6; }},
      {"trajectory.position_m", [](SimOptions& o) { o.trajectory.position_m.x() = kNan; }},
      {"trajectory.velocity_mps", [](SimOptions& o) { o.trajectory.velocity_mps.z() = kInf; }},
      {"trajectory.turn_rate_radps", [](SimOptions& o) { o.trajectory.turn_rate_radps = kNan; }},
  };
  const ArrayGeometry array = Tetrahedron();
  for (const BadOption& bad : cases) {
    SimOptions o = Stationary(Vec3(6.0, 3.0, -7.0));
    bad.spoil(o);
    const Status status = o.Validate();
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << bad.field;
    EXPECT_EQ(status.message().rfind(bad.field, 0), 0u) << status.message();
    const StatusOr<SimResult> r = Simulate(array, o);
    ASSERT_FALSE(r.ok()) << bad.field;
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  }
  SimOptions o = Stationary(Vec3(6.0, 3.0, -7.0));
  o.sample_rate_hz = kNan;
  EXPECT_NE(o.Validate().message().find("nan"), std::string::npos) << o.Validate().message();
}

TEST(Simulator, OptionsBadForThisArrayAreInvalidArguments) {
  const ArrayGeometry array = Tetrahedron();
  SimOptions fast = Stationary(Vec3(6.0, 3.0, -7.0));
  fast.trajectory.velocity_mps = Vec3(800.0, 0.0, 0.0);  // above c / 2
  const StatusOr<SimResult> r1 = Simulate(array, fast);
  ASSERT_FALSE(r1.ok());
  EXPECT_EQ(r1.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r1.status().message().find("trajectory.velocity_mps"), std::string::npos);

  SimOptions long_run = Stationary(Vec3(6.0, 3.0, -7.0));
  long_run.duration_s = 1.5e9 / kFs;  // 1.5e9 samples per channel, 6e9 over four
  ASSERT_TRUE(long_run.Validate().ok());
  const StatusOr<SimResult> r2 = Simulate(array, long_run);
  ASSERT_FALSE(r2.ok());
  EXPECT_NE(r2.status().message().find("duration_s"), std::string::npos);

  SimOptions far = Stationary(Vec3(1e12, 0.0, -7.0));
  const StatusOr<SimResult> r3 = Simulate(array, far);
  ASSERT_FALSE(r3.ok());
  EXPECT_NE(r3.status().message().find("trajectory.position_m"), std::string::npos);
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
