// The GPU particle filter's algorithm, run on the host (pf_host_model.h: the kernels'
// sequence over the same descriptors and per-particle maths), against the CPU filter on
// the CPU tests' scenarios. Runs without a device; the kernels themselves are checked
// against it statistically in particle_bank_test.cc where a GPU is present.
//
// gpu/filters is compiled only in CUDA builds (gpu/CMakeLists.txt); elsewhere this test
// reports itself skipped.
#if defined(LOCALIZER_HAVE_CUDA)

#include "tests/gpu/pf_host_model.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "tests/gpu/pf_test_scenarios.h"

namespace localizer::gpu::testing {
namespace {

double ModelCvRmse(const CvScenario& s, const engine::ParticleFilterOptions& options, uint64_t noise_seed,
                   int* fallbacks = nullptr) {
  HostBankModel model(s.array, options);
  const engine::TrackState belief = s.Belief();
  model.InitialiseGaussian(belief.mean, CovarianceRoot(belief.covariance));
  std::vector<int> used(static_cast<size_t>(s.array.pair_count()), 1);
  std::vector<double> sigmas(used.size(), options.tdoa_sigma_s);
  return CvRmse(s, noise_seed, [&](double dt_s, const engine::Measurement& m) {
    pf::StepOutput out{};
    EXPECT_TRUE(model.Step(dt_s, &m, used.data(), sigmas.data(), &out).ok());
    if (fallbacks != nullptr) *fallbacks += out.cholesky_fallback;
    return model.State(out).mean;
  });
}

// The brief's criterion: RMSE within 10 % of the CPU filter's on simulated tracks, on the
// scenario where that is decidable (see WellConditionedScenario). Both filters see the same
// measurements per noise seed.
TEST(PfHostModel, RmseWithinTenPercentOfTheCpuFilter) {
  const CvScenario s = WellConditionedScenario();
  const int runs = 40;
  int fallbacks = 0;
  const double cpu =
      PooledRmse([&](uint64_t seed) { return CpuCvRmse(s, CvOptions(kComparisonParticles, 100 + seed), seed); }, runs);
  const double model = PooledRmse(
      [&](uint64_t seed) { return ModelCvRmse(s, CvOptions(kComparisonParticles, 100 + seed), seed, &fallbacks); },
      runs);
  std::printf("pooled rmse over %d runs: cpu %.4f m, gpu model %.4f m (ratio %.3f), cholesky fallbacks %d\n", runs, cpu,
              model, model / cpu, fallbacks);
  EXPECT_LT(model, 1.10 * cpu);
  EXPECT_GT(model, 0.90 * cpu);
  EXPECT_EQ(fallbacks, 0);
}

// The CPU tests' moving-source scenario: no 10 % claim (see WellConditionedScenario: the
// median of 40 runs moves by +-20 % with the filter seeds alone), but the typical run must
// track no worse than the CPU's.
TEST(PfHostModel, MedianRmseOnTheCpuTestScenarioIsNoWorseThanTheCpus) {
  const CvScenario s;
  std::vector<double> cpu, model;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    cpu.push_back(CpuCvRmse(s, CvOptions(4096, 100 + seed), seed));
    model.push_back(ModelCvRmse(s, CvOptions(4096, 100 + seed), seed));
  }
  std::sort(cpu.begin(), cpu.end());
  std::sort(model.begin(), model.end());
  std::printf("median rmse over 40 runs: cpu %.4f m, gpu model %.4f m\n", cpu[20], model[20]);
  EXPECT_LT(model[20], 1.3 * cpu[20]);
}

// A stationary source with exact TDOAs: the mean converges to it and the cloud shrinks.
TEST(PfHostModel, StationarySourceWithExactTdoasConverges) {
  CvScenario s = WellConditionedScenario();
  s.sigma_s = 0.0;  // exact TDOAs; the filter still assumes 8 us
  HostBankModel model(s.array, CvOptions(4096, 7));
  const engine::TrackState belief = s.Belief();
  model.InitialiseGaussian(belief.mean, CovarianceRoot(belief.covariance));
  std::vector<int> used(3, 1);
  std::vector<double> sigmas(3, 8e-6);
  std::mt19937_64 rng(1);
  pf::StepOutput out{};
  for (int f = 0; f < 40; ++f) {
    const engine::Measurement m = MakeMeasurement(s.array, s.p0, s.v, f * s.hop_s, 0.0, s.fs, rng);
    ASSERT_TRUE(model.Step(f > 0 ? s.hop_s : 0.0, &m, used.data(), sigmas.data(), &out).ok());
  }
  const engine::TrackState state = model.State(out);
  EXPECT_LT((state.mean.head<3>() - s.p0).norm(), 0.05) << state.mean.transpose();
  const double trace = state.covariance.topLeftCorner<3, 3>().trace();
  const double initial_trace = belief.covariance.topLeftCorner<3, 3>().trace();
  EXPECT_LT(trace, 0.01 * initial_trace);
  EXPECT_GT(trace, 0.0);
}

// The CPU test of the GCC likelihood (tests/filters/particle_filter_test.cc): each pair's
// GCC holds the true peak (0.6) and a stronger false one (1.0) 12 samples off; the cloud
// must settle on the true lags.
TEST(PfHostModel, GccLikelihoodIgnoresAStrongerFalsePeak) {
  const engine::ArrayGeometry array = Tetrahedron(2.0, engine::Vec3(0, 0, -10), 1500.0);
  const double fs = 11025.0;
  const engine::Vec3 truth(5.0, 3.0, -9.0);
  engine::ParticleFilterOptions o = CvOptions(4096, 42);
  o.likelihood = engine::Likelihood::kGcc;
  HostBankModel model(array, o);
  engine::TrackState belief;
  belief.mean << truth.x() + 0.4, truth.y() - 0.4, truth.z(), 0, 0, 0;
  belief.covariance.diagonal() << 0.5, 0.5, 0.5, 0.1, 0.1, 0.1;
  model.InitialiseGaussian(belief.mean, CovarianceRoot(belief.covariance));
  const Eigen::VectorXd h = array.Tdoa(truth);
  engine::Measurement m;
  m.sample_rate_hz = fs;
  for (int p = 0; p < array.pair_count(); ++p) {
    engine::PairMeasurement pm;
    pm.sensor = array.sensor_of_pair(p);
    pm.peak_snr = 40.0;
    const int max_lag = static_cast<int>(std::ceil(array.max_delay_s(p) * fs)) + 14;
    pm.first_lag_samples = -max_lag;
    const double true_lag = h(p) * fs, false_lag = true_lag + 12.0;
    for (int lag = -max_lag; lag <= max_lag; ++lag) {
      const double g =
          0.6 * std::exp(-0.5 * std::pow(lag - true_lag, 2)) + std::exp(-0.5 * std::pow(lag - false_lag, 2));
      pm.gcc.push_back(static_cast<float>(g));
    }
    pm.delay_s = false_lag / fs;
    m.pairs.push_back(pm);
  }
  std::vector<int> used(3, 1);
  std::vector<double> sigmas(3, o.tdoa_sigma_s);
  pf::StepOutput out{};
  for (int f = 0; f < 20; ++f) ASSERT_TRUE(model.Step(0.1, &m, used.data(), sigmas.data(), &out).ok());
  const Eigen::VectorXd lag_error = (array.Tdoa(model.State(out).mean.head<3>()) - h) * fs;
  EXPECT_LT(lag_error.cwiseAbs().maxCoeff(), 0.5) << lag_error.transpose();
}

// Innovation moments as the CPU reports them: all particles at one state, so each pair's
// mean innovation is d - h(state), and the NIS the CPU filter computes from them matches.
TEST(PfHostModel, InnovationsMatchTheCpuFilterOnAPointCloud) {
  const CvScenario s;
  engine::ParticleFilterOptions o = CvOptions(256, 3);
  engine::TrackState point;
  point.mean << 5.0, -3.0, -8.5, -1.0, 0.8, 0.1;  // covariance 0: every particle at the mean
  auto cpu = std::move(engine::ParticleFilter::Create(s.array, o)).value();
  ASSERT_TRUE(cpu->Initialise(point).ok());
  HostBankModel model(s.array, o);
  model.InitialiseGaussian(point.mean, engine::Mat6::Zero());
  std::mt19937_64 rng(2);
  const engine::Measurement m = MakeMeasurement(s.array, s.p0, s.v, 1.0, 8e-6, s.fs, rng);
  const auto report = cpu->Update(m);
  ASSERT_TRUE(report.ok());
  std::vector<int> used(3, 1);
  std::vector<double> sigmas(3, o.tdoa_sigma_s);
  pf::StepOutput out{};
  ASSERT_TRUE(model.Step(0.0, &m, used.data(), sigmas.data(), &out).ok());
  double nis = 0.0;
  for (int p = 0; p < 3; ++p) {
    const double mean_s = out.sum_e[p] * sigmas[p];
    const double var_s2 = std::max(0.0, out.sum_e2[p] - out.sum_e[p] * out.sum_e[p]) * sigmas[p] * sigmas[p];
    nis += mean_s * mean_s / (sigmas[p] * sigmas[p] + var_s2);
  }
  EXPECT_GT(report->nis, 1.0);  // the point is off the source: a clear innovation
  EXPECT_NEAR(nis, report->nis, 1e-4 * report->nis);
}

}  // namespace
}  // namespace localizer::gpu::testing

#else  // !LOCALIZER_HAVE_CUDA

#include <gtest/gtest.h>

TEST(PfHostModel, NeedsTheCudaBuild) { GTEST_SKIP() << "built without CUDA: gpu/filters is not compiled"; }

#endif  // LOCALIZER_HAVE_CUDA
