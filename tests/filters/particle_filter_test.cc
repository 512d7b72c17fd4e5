// Particle filter on synthetic TDOA measurements drawn from the model with known noise, so
// accuracy can be compared with the per-frame Cramer–Rao bound directly.
#include "engine/filters/particle_filter.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <tuple>

#include "engine/array/multilateration.h"
#include "engine/filters/particle_set.h"
#include "tests/filters/tdoa_frames.h"

namespace localizer::engine {
namespace {

struct RunResult {
  double rmse_m = 0.0;
  double crlb_m = 0.0;  // per-frame position CRLB, RMS over the run
  std::vector<Vec6> states;
};

// outlier_every > 0: every outlier_every-th frame one pair (in turn) reports a delay 6-12
// sigma off (a reflection close behind the direct path won its peak): far enough to drag
// a Gaussian, near enough that every particle still sees it inside the likelihood's range.
// from_fix: start as a session does, from a multilateration fix (position spread the
// frame's CRLB, 1 std off the truth on every axis) instead of the 1 m box-like belief.
RunResult RunCv(const ParticleFilterOptions& options, uint64_t noise_seed, int frames = 60, int outlier_every = 0,
                bool from_fix = false) {
  const ArrayGeometry array = Tetrahedron(2.0, Vec3(0, 0, -10), 1500.0);
  const Vec3 p0(6.0, -4.0, -8.0), v(-1.2, 0.9, 0.0);
  const double fs = 11025.0, hop_s = 2048.0 / fs, sigma_s = 8e-6;
  std::mt19937_64 rng(noise_seed);
  auto pf = ParticleFilter::Create(array, options);
  EXPECT_TRUE(pf.ok());
  TrackState belief;
  belief.mean << p0.x() + 0.5, p0.y() - 0.5, p0.z() + 0.3, 0, 0, 0;
  belief.covariance.diagonal() << 1, 1, 1, 4, 4, 4;
  if (from_fix) {
    const Mat3 fix_cov = TdoaPositionCrlb(array, p0, sigma_s);
    belief.mean.head<3>() = p0 + fix_cov.diagonal().cwiseSqrt();
    belief.covariance.topLeftCorner<3, 3>() = fix_cov;
  }
  EXPECT_TRUE((*pf)->Initialise(belief).ok());
  RunResult out;
  double se = 0.0, crlb2 = 0.0;
  int scored = 0;
  for (int f = 0; f < frames; ++f) {
    const double t = f * hop_s;
    if (f > 0) (*pf)->Predict(hop_s);
    Measurement m = MakeMeasurement(array, p0, v, t, sigma_s, fs, rng);
    if (outlier_every > 0 && f % outlier_every == 0) {
      const int pair = (f / outlier_every) % array.pair_count();
      std::uniform_real_distribution<double> offset(6.0, 12.0);
      m.pairs[pair].delay_s += (f % 2 == 0 ? 1.0 : -1.0) * offset(rng) * sigma_s;
    }
    auto report = (*pf)->Update(m);
    EXPECT_TRUE(report.ok());
    const TrackState s = (*pf)->State();
    out.states.push_back(s.mean);
    if (f >= frames / 4) {  // after convergence
      const Vec3 truth = p0 + v * t;
      se += (s.mean.head<3>() - truth).squaredNorm();
      crlb2 += TdoaPositionCrlb(array, truth, sigma_s).trace();
      ++scored;
    }
  }
  out.rmse_m = std::sqrt(se / scored);
  out.crlb_m = std::sqrt(crlb2 / scored);
  return out;
}

ParticleFilterOptions Options(Likelihood likelihood = Likelihood::kPeak) {
  ParticleFilterOptions o;
  o.particles = 4096;
  o.accel_noise_mps2 = 0.05;
  o.tdoa_sigma_s = 8e-6;
  o.likelihood = likelihood;
  o.seed = 42;
  return o;
}

// A constant-velocity track (11 s passing within 2 m of the array) observed by the model it
// assumes: averaging ~45 frames through
// the motion model must beat a single frame's bound by well over 2x (the goal is
// 0.5 x CRLB; with q = 0.05 m/s^2 the steady-state gain averages ~10+ frames).
TEST(ParticleFilter, CvTrackBeatsHalfThePerFrameCrlb) {
  const RunResult r = RunCv(Options(), 1);
  EXPECT_LT(r.rmse_m, 0.5 * r.crlb_m) << "rmse " << r.rmse_m << " crlb " << r.crlb_m;
}

TEST(ParticleFilter, VelocityConverges) {
  const RunResult r = RunCv(Options(), 2);
  const Vec6& last = r.states.back();
  EXPECT_NEAR(last(kVx), -1.2, 0.3);
  EXPECT_NEAR(last(kVy), 0.9, 0.3);
  EXPECT_NEAR(last(kVz), 0.0, 0.3);
}

TEST(ParticleFilter, SameSeedSameOutputOtherSeedOtherOutput) {
  const RunResult a = RunCv(Options(), 5, 30), b = RunCv(Options(), 5, 30);
  ParticleFilterOptions other = Options();
  other.seed = 43;
  const RunResult c = RunCv(other, 5, 30);
  for (size_t i = 0; i < a.states.size(); ++i) EXPECT_EQ(a.states[i], b.states[i]);
  EXPECT_NE(a.states.back(), c.states.back());
}

TEST(ParticleFilter, GccLikelihoodIgnoresAStrongerFalsePeak) {
  // Each pair's GCC holds the true peak (0.6) and a stronger false one (1.0) 12 samples off,
  // as a surface reflection would. The peak delay points at the false one; the GCC
  // likelihood should still lock onto the true lag, because only the true one is
  // consistent across pairs and frames with the initial belief.
  const ArrayGeometry array = Tetrahedron(2.0, Vec3(0, 0, -10), 1500.0);
  const double fs = 11025.0;
  const Vec3 truth(5.0, 3.0, -9.0);
  auto pf = ParticleFilter::Create(array, Options(Likelihood::kGcc));
  ASSERT_TRUE(pf.ok());
  TrackState belief;
  belief.mean << truth.x() + 0.4, truth.y() - 0.4, truth.z(), 0, 0, 0;
  belief.covariance.diagonal() << 0.5, 0.5, 0.5, 0.1, 0.1, 0.1;
  ASSERT_TRUE((*pf)->Initialise(belief).ok());
  const Eigen::VectorXd h = array.Tdoa(truth);
  Measurement m;
  m.sample_rate_hz = fs;
  for (int p = 0; p < array.pair_count(); ++p) {
    PairMeasurement pm;
    pm.sensor = array.sensor_of_pair(p);
    pm.peak_snr = 40.0;
    const int max_lag = static_cast<int>(std::ceil(array.max_delay_s(p) * fs)) + 14;
    pm.first_lag_samples = -max_lag;
    const double true_lag = h(p) * fs, false_lag = true_lag + 12.0;
    for (int lag = -max_lag; lag <= max_lag; ++lag) {
      const double g = 0.6 * std::exp(-0.5 * std::pow((lag - true_lag) / 1.0, 2)) +
                       1.0 * std::exp(-0.5 * std::pow((lag - false_lag) / 1.0, 2));
      pm.gcc.push_back(static_cast<float>(g));
    }
    pm.delay_s = false_lag / fs;
    m.pairs.push_back(pm);
  }
  for (int f = 0; f < 20; ++f) {
    (*pf)->Predict(0.1);
    ASSERT_TRUE((*pf)->Update(m).ok());
  }
  // A 1-sample-wide GCC peak at 5.8 m leaves the range loose, so judge in delay space:
  // the estimate's delays sit on the true peak, 12 samples from the false one.
  const Eigen::VectorXd lag_error = (array.Tdoa((*pf)->State().mean.head<3>()) - h) * fs;
  EXPECT_LT(lag_error.cwiseAbs().maxCoeff(), 0.5) << lag_error.transpose();
}

// Pairs whose GCC peak is no higher than noise alone makes it carry no source: the update
// must leave the belief as it was; one detected pair is still used.
TEST(ParticleFilter, PairsWithoutADetectionAreLeftOut) {
  const ArrayGeometry array = Tetrahedron(2.0, Vec3(0, 0, -10), 1500.0);
  auto pf = std::move(*ParticleFilter::Create(array, Options()));
  TrackState belief;
  belief.mean << 4, 2, -9, 0, 0, 0;
  belief.covariance.diagonal() << 1, 1, 1, 0.1, 0.1, 0.1;
  ASSERT_TRUE(pf->Initialise(belief).ok());
  std::mt19937_64 rng(8);
  Measurement m = MakeMeasurement(array, Vec3(4.5, 2.5, -9.0), Vec3::Zero(), 0.0, 8e-6, 11025.0, rng);
  for (PairMeasurement& pm : m.pairs) pm.peak_snr = 3.0;  // noise level
  const TrackState before = pf->State();
  auto report = pf->Update(m);
  ASSERT_TRUE(report.ok());
  EXPECT_EQ(report->pair_count, 0);
  EXPECT_EQ(pf->State().mean, before.mean);
  m.pairs[1].peak_snr = 30.0;
  report = pf->Update(m);
  ASSERT_TRUE(report.ok());
  EXPECT_EQ(report->pair_count, 1);
  EXPECT_NE(pf->State().mean, before.mean);
}

TEST(ParticleFilter, MixtureLikelihoodShrugsOffOutlierPairsTheGaussianFollows) {
  // One pair in every third frame is 6-12 sigma off: an outlier rate of 1/9 per pair and
  // frame, which the mixture is told (eps 0.15). The same likelihood with eps 0 is the plain
  // Gaussian and is dragged by it; the Student-t peak likelihood is printed for comparison.
  // Gaussian cores are sharp against this 1 m start (TDOAs fix the bearing to
  // millimetres), so both run with the full Silverman kernel (kernel_scale 1), which keeps
  // the cloud from collapsing onto a few particles.
  double mixture = 0.0, gaussian = 0.0, clean = 0.0, student = 0.0;
  for (uint64_t seed : {11u, 12u, 13u, 14u}) {
    ParticleFilterOptions o = Options(Likelihood::kMixture);
    o.kernel_scale = 1.0;
    o.outlier_probability = 0.15;
    mixture += RunCv(o, seed, 60, 3).rmse_m / 4.0;
    clean += RunCv(o, seed, 60, 0).rmse_m / 4.0;
    o.outlier_probability = 0.0;
    gaussian += RunCv(o, seed, 60, 3).rmse_m / 4.0;
    student += RunCv(Options(Likelihood::kPeak), seed, 60, 3).rmse_m / 4.0;
  }
  std::printf(
      "rmse with outliers: mixture %.3f m, gaussian %.3f m, student-t peak %.3f m; "
      "mixture without outliers %.3f m\n",
      mixture, gaussian, student, clean);
  EXPECT_LT(mixture, 0.1 * gaussian);
  EXPECT_LT(mixture, 2.0 * clean);
  EXPECT_LT(clean, 0.15);
}

TEST(ParticleFilter, ContractErrors) {
  const ArrayGeometry array = Tetrahedron(2.0, Vec3::Zero(), 343.0);
  ParticleFilterOptions bad = Options();
  bad.particles = 3;
  EXPECT_EQ(ParticleFilter::Create(array, bad).status().code(), StatusCode::kInvalidArgument);
  bad = Options();
  bad.resample_threshold = 1.5;
  EXPECT_EQ(ParticleFilter::Create(array, bad).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ParseLikelihood("nope").status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(*ParseLikelihood("mixture"), Likelihood::kMixture);
  bad = Options(Likelihood::kMixture);
  bad.outlier_probability = 1.0;
  EXPECT_NE(ParticleFilter::Create(array, bad).status().message().find("outlier_probability"), std::string::npos);

  auto pf = ParticleFilter::Create(array, Options());
  ASSERT_TRUE(pf.ok());
  Measurement m;
  m.sample_rate_hz = 48000;
  m.pairs.resize(3);
  EXPECT_EQ((*pf)->Update(m).status().code(), StatusCode::kFailedPrecondition);
  TrackState belief;
  belief.covariance = Mat6::Identity();
  ASSERT_TRUE((*pf)->Initialise(belief).ok());
  m.pairs.resize(2);
  EXPECT_EQ((*pf)->Update(m).status().code(), StatusCode::kInvalidArgument);
  belief.covariance(0, 0) = -1.0;
  EXPECT_EQ((*pf)->Initialise(belief).code(), StatusCode::kInvalidArgument);
}

TEST(ParticleFilter, InitialiseMatchesTheRequestedBelief) {
  const ArrayGeometry array = Tetrahedron(2.0, Vec3::Zero(), 343.0);
  ParticleFilterOptions o = Options();
  o.particles = 1 << 16;
  auto pf = ParticleFilter::Create(array, o);
  ASSERT_TRUE(pf.ok());
  TrackState belief;
  belief.mean << 3, -2, 1, 0.5, 0, -0.5;
  belief.covariance.diagonal() << 0.25, 1.0, 4.0, 0.01, 0.04, 0.09;
  belief.covariance(0, 1) = belief.covariance(1, 0) = 0.3;
  ASSERT_TRUE((*pf)->Initialise(belief).ok());
  const TrackState s = (*pf)->State();
  // 65536 draws: standard error of a mean ~ sigma / 256, of a variance ~ 0.6 %.
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(s.mean(k), belief.mean(k), 5.0 * std::sqrt(belief.covariance(k, k)) / 256.0) << k;
    EXPECT_NEAR(s.covariance(k, k), belief.covariance(k, k), 0.04 * belief.covariance(k, k)) << k;
  }
  EXPECT_NEAR(s.covariance(0, 1), 0.3, 0.02);
}

TEST(ParticleFilter, MeanRevertingVelocityDecaysByTheTimeConstant) {
  // No acceleration noise: the prediction is deterministic, v' = d v, p' = p + tau (1 - d) v.
  const ArrayGeometry array = Tetrahedron(2.0, Vec3::Zero(), 343.0);
  for (double tau_s : {0.0, 10.0, 1.0}) {
    ParticleFilterOptions o = Options();
    o.SetSingleMotion();  // no turn rates or speed changes: the mean velocity is kept
    o.accel_noise_mps2 = 0.0;
    o.velocity_time_constant_s = tau_s;
    auto pf = ParticleFilter::Create(array, o);
    ASSERT_TRUE(pf.ok());
    TrackState belief;
    belief.mean << 3, -2, 1, 2.0, -1.0, 0.5;
    belief.covariance = 1e-8 * Mat6::Identity();
    ASSERT_TRUE((*pf)->Initialise(belief).ok());
    const double dt_s = 0.5;
    (*pf)->Predict(dt_s);
    const TrackState s = (*pf)->State();
    const double d = tau_s > 0.0 ? std::exp(-dt_s / tau_s) : 1.0;
    const double reach_s = tau_s > 0.0 ? tau_s * (1.0 - d) : dt_s;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(s.mean(3 + k), d * belief.mean(3 + k), 1e-4) << "tau " << tau_s << " axis " << k;
      EXPECT_NEAR(s.mean(k), belief.mean(k) + reach_s * belief.mean(3 + k), 1e-4) << "tau " << tau_s << " axis " << k;
    }
  }
  ParticleFilterOptions bad = Options();
  bad.velocity_time_constant_s = -1.0;
  EXPECT_EQ(ParticleFilter::Create(array, bad).status().code(), StatusCode::kInvalidArgument);
}

TEST(ParticleFilter, ManoeuvresKeepTheAccelerationVarianceAndFattenItsTails) {
  // From a point, one step of dt gives velocity changes a dt per axis. White acceleration:
  // variance (sigma dt)^2, kurtosis 3. Manoeuvres (share p, scale k): the same variance,
  // kurtosis 3 (1 - p + p k^4) / (1 - p + p k^2)^2 = 25.0 at p = 0.1, k = 10 (a scale
  // mixture of normals), so the quiet particles' spread is 1 / sqrt(10.9) of the RMS.
  const ArrayGeometry array = Tetrahedron(2.0, Vec3::Zero(), 343.0);
  const double sigma = 2.0, dt_s = 0.25, scale = 10.0;
  for (double share : {0.0, 0.1}) {
    ParticleFilterOptions o = Options();
    o.particles = 1 << 18;
    ParticleSet set(array, o);
    set.SetManoeuvre(share, scale);
    set.SampleGaussian(Vec6::Zero(), Mat6::Zero());
    set.Predict(dt_s, sigma);
    const double expected_var = sigma * sigma * dt_s * dt_s;
    const double expected_kurtosis =
        3.0 * (1.0 - share + share * std::pow(scale, 4)) / std::pow(1.0 - share + share * scale * scale, 2);
    const double quiet_sd = std::sqrt(expected_var) * ManoeuvreGainsFor(share, scale).quiet;
    for (int k = 3; k < 6; ++k) {
      const float* v = set.columns()[static_cast<size_t>(k)];
      double m2 = 0.0, m4 = 0.0;
      int beyond = 0;  // beyond 4 quiet sds: ~6e-5 of the quiet ones, most of the manoeuvring
      for (int i = 0; i < o.particles; ++i) {
        const double x = v[i];
        m2 += x * x;
        m4 += x * x * x * x;
        beyond += std::abs(x) > 4.0 * quiet_sd;
      }
      m2 /= o.particles;
      m4 /= o.particles;
      EXPECT_NEAR(m2, expected_var, 0.03 * expected_var) << "share " << share << " axis " << k;
      EXPECT_NEAR(m4 / (m2 * m2), expected_kurtosis, 0.15 * expected_kurtosis) << "share " << share << " axis " << k;
      // Manoeuvring draws beyond 4 quiet sds (0.4 of their own sds): 69 % of them.
      const double expected_beyond = share * 0.689;
      EXPECT_NEAR(static_cast<double>(beyond) / o.particles, expected_beyond, 0.1 * expected_beyond + 2e-4)
          << "share " << share << " axis " << k;
    }
  }
  EXPECT_NEAR(ManoeuvreGainsFor(0.1, 10.0).quiet, 1.0 / std::sqrt(10.9), 1e-12);
  EXPECT_NEAR(ManoeuvreGainsFor(0.1, 10.0).manoeuvre, 10.0 / std::sqrt(10.9), 1e-12);
  ParticleFilterOptions bad = Options();
  bad.manoeuvre_share = 1.0;
  EXPECT_NE(ParticleFilter::Create(array, bad).status().message().find("manoeuvre_share"), std::string::npos);
  bad = Options();
  bad.manoeuvre_scale = 0.5;
  EXPECT_NE(ParticleFilter::Create(array, bad).status().message().find("manoeuvre_scale"), std::string::npos);
}

TEST(ParticleFilter, AccelerationLevelsScaleTheWhiteAccelerationLogUniformly) {
  // Gains log-uniform in [f, c]: one step of dt from a point gives velocity changes of
  // variance (sigma dt)^2 E[g^2] per axis, E[g^2] = (c^2 - f^2) / (2 ln(c / f)).
  const ArrayGeometry array = Tetrahedron(2.0, Vec3::Zero(), 343.0);
  const double sigma = 2.0, dt_s = 0.25, floor = 0.01, ceiling = 1.0;
  ParticleFilterOptions o = Options();
  o.particles = 1 << 18;
  ParticleSet set(array, o);
  set.SetAccelLevels(floor, ceiling, 0.0);
  set.SampleGaussian(Vec6::Zero(), Mat6::Zero());
  set.Predict(dt_s, sigma);
  const double mean_g2 = (ceiling * ceiling - floor * floor) / (2.0 * std::log(ceiling / floor));
  const double expected_var = sigma * sigma * dt_s * dt_s * mean_g2;
  for (int k = 3; k < 6; ++k) {
    const float* v = set.columns()[static_cast<size_t>(k)];
    double m2 = 0.0;
    int quiet = 0;  // |dv| below 0.1 sigma dt: most of the particles whose gain is below 0.1
    for (int i = 0; i < o.particles; ++i) {
      m2 += static_cast<double>(v[i]) * v[i];
      quiet += std::abs(v[i]) < 0.1 * sigma * dt_s;
    }
    EXPECT_NEAR(m2 / o.particles, expected_var, 0.03 * expected_var) << "axis " << k;
    // Half the gains lie below 0.1 (the log-midpoint); a plain normal of the RMS would put
    // only 14 % of its draws that close to zero.
    EXPECT_GT(static_cast<double>(quiet) / o.particles, 0.4) << "axis " << k;
  }
  EXPECT_TRUE(ParticleFilterOptions{}.accel_levels()) << "on by default (the nineteenth pass)";
  ParticleFilterOptions bad = Options();
  bad.accel_level_floor = 2.0;
  bad.accel_level_ceiling = 1.0;
  EXPECT_NE(ParticleFilter::Create(array, bad).status().message().find("accel_level_floor"), std::string::npos);
  bad = Options();
  bad.accel_level_switch_hz = -1.0;
  EXPECT_NE(ParticleFilter::Create(array, bad).status().message().find("accel_level_switch_hz"), std::string::npos);
}

// A source that sits still for 6 s, then moves off at 1.5 m/s, tracked with the session's
// acceleration std (1 m/s^2): with acceleration levels the quiet particles win while it
// sits (frames average over seconds) and the loud ones when it starts.
struct StillThenMovingResult {
  double still_rmse_m = 0.0, moving_rmse_m = 0.0, crlb_m = 0.0;
};
StillThenMovingResult RunStillThenMoving(bool levels, uint64_t noise_seed) {
  const ArrayGeometry array = Tetrahedron(2.0, Vec3(0, 0, -10), 1500.0);
  const Vec3 p0(1.5, -1.0, -9.0), v(1.5, 0.0, 0.0);
  const double fs = 11025.0, hop_s = 2048.0 / fs, sigma_s = 8e-6, start_s = 6.0;
  ParticleFilterOptions o = Options();
  o.accel_noise_mps2 = 1.0;
  o.SetSingleMotion();  // the levels alone against one std
  if (levels) {
    std::tie(o.accel_level_floor, o.accel_level_ceiling, o.accel_level_switch_hz) = std::tuple(0.003, 3.0, 1.0);
  }
  auto pf = ParticleFilter::Create(array, o);
  EXPECT_TRUE(pf.ok());
  TrackState belief;
  const Mat3 fix_cov = TdoaPositionCrlb(array, p0, sigma_s);
  belief.mean.head<3>() = p0 + fix_cov.diagonal().cwiseSqrt();
  belief.covariance.topLeftCorner<3, 3>() = fix_cov;
  belief.covariance.bottomRightCorner<3, 3>() = 0.25 * Mat3::Identity();
  EXPECT_TRUE((*pf)->Initialise(belief).ok());
  std::mt19937_64 rng(noise_seed);
  double still_se = 0.0, moving_se = 0.0, crlb2 = 0.0;
  int still = 0, moving = 0;
  const int frames = static_cast<int>(10.0 / hop_s);
  for (int f = 0; f < frames; ++f) {
    const double t = f * hop_s;
    if (f > 0) (*pf)->Predict(hop_s);
    const bool moved = t >= start_s;
    // Moving: p0 + v (t - start), i.e. p0 - v start + v t.
    const Measurement m = moved ? MakeMeasurement(array, p0 - v * start_s, v, t, sigma_s, fs, rng)
                                : MakeMeasurement(array, p0, Vec3::Zero(), t, sigma_s, fs, rng);
    EXPECT_TRUE((*pf)->Update(m).ok());
    const Vec3 truth = moved ? Vec3(p0 + v * (t - start_s)) : p0;
    const double e2 = ((*pf)->State().mean.head<3>() - truth).squaredNorm();
    if (t >= 2.0 && !moved) {
      still_se += e2;
      crlb2 += TdoaPositionCrlb(array, truth, sigma_s).trace();
      ++still;
    }
    if (t >= start_s + 2.0) {  // two seconds to take up the new motion
      moving_se += e2;
      ++moving;
    }
  }
  return {std::sqrt(still_se / still), std::sqrt(moving_se / moving), std::sqrt(crlb2 / still)};
}

// Three seeds, pooled: one run's error varies by 2x between seeds (the moving leg's bound
// grows as the source leaves), and the claim is about the filter, not a seed. Measured:
// still 0.52-0.89 x the error without levels (mean 0.69), moving pooled 0.97 x.
TEST(ParticleFilter, AccelerationLevelsAverageAStillSourceAndFollowItWhenItMoves) {
  double ratio_still = 0.0, moving_on2 = 0.0, moving_off2 = 0.0;
  for (uint64_t seed : {1u, 2u, 3u}) {
    const StillThenMovingResult on = RunStillThenMoving(true, seed), off = RunStillThenMoving(false, seed);
    std::printf("seed %llu: still rmse %.4f m with levels, %.4f m without (crlb %.4f m); moving %.4f / %.4f m\n",
                static_cast<unsigned long long>(seed), on.still_rmse_m, off.still_rmse_m, on.crlb_m, on.moving_rmse_m,
                off.moving_rmse_m);
    ratio_still += on.still_rmse_m / off.still_rmse_m / 3.0;
    EXPECT_LT(on.still_rmse_m, on.crlb_m) << "seed " << seed;  // frames average
    moving_on2 += on.moving_rmse_m * on.moving_rmse_m;
    moving_off2 += off.moving_rmse_m * off.moving_rmse_m;
  }
  EXPECT_LT(ratio_still, 0.8) << "levels should cut a still source's error";
  EXPECT_LT(std::sqrt(moving_on2), 1.3 * std::sqrt(moving_off2)) << "levels should take up the start";
}

}  // namespace
}  // namespace localizer::engine
