#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "engine/experiments/pf_vs_ekf_2d.h"
#include "engine/experiments/planar_kalman.h"
#include "engine/experiments/planar_particle.h"

namespace localizer::engine::experiments {
namespace {

std::shared_ptr<const MixtureDensity> Density(const MixtureNoise& noise) {
  StatusOr<MixtureDensity> density = MixtureDensity::Create(noise);
  EXPECT_TRUE(density.ok()) << density.status().ToString();
  return density.ok() ? std::make_shared<const MixtureDensity>(std::move(*density)) : nullptr;
}

// Exact fixes, and every filter told the sensor is good to 5 cm (the Gaussian component's
// sigma, which also sets sigma_R): each must follow the truth, which wanders off the course
// by the control errors, to within a few centimetres once the 0.5 m prior has been
// corrected (20 steps: 100 particles drawn from it need a few fixes to find the truth).
TEST(PlanarFilters, NoiseFreeFixesAreTrackedToNearZero) {
  PfVsEkf2dOptions options;
  options.seed = 404;
  options.measurement_noise.gaussian_sigma_m = 0.05;
  const auto density = Density(options.measurement_noise);
  for (int run = 0; run < 2; ++run) {
    StatusOr<PlanarRun> simulated = SimulatePlanarRun(options, run);
    ASSERT_TRUE(simulated.ok()) << simulated.status().ToString();
    for (size_t k = 0; k < simulated->fixes_m.size(); ++k) {
      simulated->fixes_m[k] = simulated->truth[k + 1].head<2>();
    }
    // The truth does leave the nominal course (else following it would prove nothing).
    EXPECT_GT((simulated->truth.back().head<2>()).norm(), 1.0);
    for (const std::string& name : PfVsEkf2dFilterNames()) {
      StatusOr<std::unique_ptr<PlanarFilter>> filter = MakePlanarFilter(name, options, density, run);
      ASSERT_TRUE(filter.ok()) << name << ": " << filter.status().ToString();
      const std::vector<double> errors = TrackPlanarRun(**filter, options, *simulated);
      double sum = 0.0, worst = 0.0;
      for (size_t k = 0; k < errors.size(); ++k) {
        sum += errors[k];
        if (k >= 20) worst = std::max(worst, errors[k]);
      }
      EXPECT_LT(sum / static_cast<double>(errors.size()), 0.03) << name << " run " << run;
      EXPECT_LT(worst, 0.1) << name << " run " << run;
    }
  }
}

PlanarBelief StartBelief() {
  PlanarBelief belief;
  belief.covariance.diagonal() << 0.25, 0.25, 0.0025;
  return belief;
}

std::unique_ptr<PlanarKalmanFilter> Kalman(PlanarPredictor predictor, PlanarUpdater updater, double c = 1.345,
                                           double nu = 3.0) {
  PlanarKalmanOptions options;
  options.predictor = predictor;
  options.updater = updater;
  options.huber_threshold = c;
  options.student_dof = nu;
  StatusOr<std::unique_ptr<PlanarKalmanFilter>> filter =
      PlanarKalmanFilter::Create(BicycleModel(), ControlNoise(), options);
  EXPECT_TRUE(filter.ok()) << filter.status().ToString();
  (*filter)->Initialise(StartBelief());
  return std::move(*filter);
}

std::unique_ptr<PlanarKalmanFilter> NoiselessKalman(PlanarPredictor predictor, double heading_var) {
  PlanarKalmanOptions options;
  options.predictor = predictor;
  StatusOr<std::unique_ptr<PlanarKalmanFilter>> filter =
      PlanarKalmanFilter::Create(BicycleModel(), ControlNoise{0.0, 0.0}, options);
  EXPECT_TRUE(filter.ok()) << filter.status().ToString();
  PlanarBelief belief;
  belief.covariance(kHeading, kHeading) = heading_var;
  (*filter)->Initialise(belief);
  return std::move(*filter);
}

TEST(PlanarKalman, OneUpdateOnTheLinearPositionModelEqualsTheTextbookStep) {
  // z = H x + n with H = [I2 0]: the update is linear, so EKF and UKF must both give
  //   K = P H^T (H P H^T + R)^-1,  x = x- + K (z - H x-),  P = (I - K H) P- (I - K H)^T + K R K^T,
  // computed here by hand from the matrices.
  PlanarBelief prior;
  prior.mean << 3.0, -1.0, 0.4;
  prior.covariance << 0.50, 0.10, 0.02,  //
      0.10, 0.30, 0.01,                  //
      0.02, 0.01, 0.04;
  const Eigen::Vector2d z(3.6, -1.5);
  const double sigma_m = 0.7;
  Eigen::Matrix<double, 2, 3> h = Eigen::Matrix<double, 2, 3>::Zero();
  h(0, 0) = h(1, 1) = 1.0;
  const Eigen::Matrix2d r = sigma_m * sigma_m * Eigen::Matrix2d::Identity();
  const Eigen::Matrix2d s = h * prior.covariance * h.transpose() + r;
  const Eigen::Matrix<double, 3, 2> k = prior.covariance * h.transpose() * s.inverse();
  const Eigen::Vector3d mean = prior.mean + k * (z - h * prior.mean);
  const Eigen::Matrix3d a = Eigen::Matrix3d::Identity() - k * h;
  const Eigen::Matrix3d cov = a * prior.covariance * a.transpose() + k * r * k.transpose();
  for (PlanarPredictor predictor : {PlanarPredictor::kExtended, PlanarPredictor::kUnscented}) {
    PlanarKalmanOptions options;
    options.predictor = predictor;
    options.measurement_sigma_m = sigma_m;
    auto filter = PlanarKalmanFilter::Create(BicycleModel(), ControlNoise(), options);
    ASSERT_TRUE(filter.ok()) << filter.status().ToString();
    (*filter)->Initialise(prior);
    (*filter)->Update(z);
    EXPECT_LT(((*filter)->Estimate() - mean).norm(), 1e-12);
    EXPECT_LT(((*filter)->belief().covariance - cov).norm(), 1e-12);
  }
}

TEST(PlanarKalman, UnscentedPredictionCapturesTheHeadingSpread) {
  // Without uncertainty both predictors are the model itself.
  auto ekf = NoiselessKalman(PlanarPredictor::kExtended, 0.0);
  auto ukf = NoiselessKalman(PlanarPredictor::kUnscented, 0.0);
  for (int k = 0; k < 5; ++k) {
    ekf->Predict({3.5, 0.3}, 0.1);
    ukf->Predict({3.5, 0.3}, 0.1);
  }
  EXPECT_LT((ekf->belief().mean - ukf->belief().mean).norm(), 1e-12);
  // Heading ~ N(0, 0.3^2), straight ahead: E[x'] = v dt E[cos theta] = v dt exp(-0.045).
  // The EKF keeps v dt (first order); the 11 sigma points give v dt (0.8 + 0.2 cos(0.3
  // sqrt(5))), within 1e-3 of the truth.
  ekf = NoiselessKalman(PlanarPredictor::kExtended, 0.09);
  ukf = NoiselessKalman(PlanarPredictor::kUnscented, 0.09);
  ekf->Predict({3.5, 0.0}, 0.1);
  ukf->Predict({3.5, 0.0}, 0.1);
  const double exact = 0.35 * std::exp(-0.045);
  EXPECT_NEAR(ekf->belief().mean.x(), 0.35, 1e-12);
  EXPECT_NEAR(ukf->belief().mean.x(), exact, 1e-3);
  EXPECT_NEAR(ukf->belief().mean.y(), 0.0, 1e-12);
  EXPECT_NEAR(ukf->belief().covariance(kHeading, kHeading), 0.09, 1e-12);
}

TEST(PlanarKalman, RobustUpdatesLimitAnOutliersPull) {
  const Eigen::Vector2d outlier(100.0, 0.0);  // 100 sigma_R off
  auto gaussian = Kalman(PlanarPredictor::kExtended, PlanarUpdater::kGaussian);
  auto huber = Kalman(PlanarPredictor::kExtended, PlanarUpdater::kHuber);
  auto student = Kalman(PlanarPredictor::kExtended, PlanarUpdater::kStudentT);
  for (PlanarKalmanFilter* f : {gaussian.get(), huber.get(), student.get()}) f->Update(outlier);
  // Gaussian: the gain 0.25 / 1.25 = 0.2 takes 20 m of the 100.
  EXPECT_NEAR(gaussian->Estimate().x(), 20.0, 1e-9);
  // Huber: the fix counts as if 1.345 sigma away: about 0.2 * 1.345 m.
  EXPECT_LT(huber->Estimate().x(), 0.5);
  EXPECT_GT(huber->Estimate().x(), 0.1);
  // Student-t: weight (3 + 1) / (3 + 100^2) ~ 4e-4: almost no pull.
  EXPECT_LT(std::abs(student->Estimate().x()), 0.05);
}

TEST(PlanarKalman, RobustUpdatesEqualTheGaussianOneOnSmallResiduals) {
  auto gaussian = Kalman(PlanarPredictor::kExtended, PlanarUpdater::kGaussian);
  auto huber = Kalman(PlanarPredictor::kExtended, PlanarUpdater::kHuber);
  auto wide_t = Kalman(PlanarPredictor::kExtended, PlanarUpdater::kStudentT, 1.345, 1e9);
  const Eigen::Vector2d fix(0.4, -0.3);  // within c sigma_R of every iterate
  for (PlanarKalmanFilter* f : {gaussian.get(), huber.get(), wide_t.get()}) f->Update(fix);
  EXPECT_LT((huber->Estimate() - gaussian->Estimate()).norm(), 1e-12);
  EXPECT_LT((wide_t->Estimate() - gaussian->Estimate()).norm(), 1e-6);
  EXPECT_LT((huber->belief().covariance - gaussian->belief().covariance).norm(), 1e-12);
}

TEST(PlanarKalman, RejectsBadOptionsNamingTheField) {
  PlanarKalmanOptions options;
  options.measurement_sigma_m = 0.0;
  EXPECT_NE(PlanarKalmanFilter::Create(BicycleModel(), ControlNoise(), options)
                .status()
                .message()
                .find("measurement_sigma_m"),
            std::string::npos);
  ControlNoise noise;
  noise.steering_sigma_rad = -1.0;
  EXPECT_NE(PlanarKalmanFilter::Create(BicycleModel(), noise, PlanarKalmanOptions())
                .status()
                .message()
                .find("steering_sigma_rad"),
            std::string::npos);
}

std::unique_ptr<PlanarParticleFilter> Particles(uint64_t seed, ParticleLikelihood likelihood,
                                                std::shared_ptr<const MixtureDensity> density) {
  PlanarParticleOptions options;
  options.likelihood = likelihood;
  StatusOr<std::unique_ptr<PlanarParticleFilter>> filter =
      PlanarParticleFilter::Create(BicycleModel(), ControlNoise(), options, std::move(density), std::mt19937_64(seed));
  EXPECT_TRUE(filter.ok()) << filter.status().ToString();
  (*filter)->Initialise(StartBelief());
  return std::move(*filter);
}

TEST(PlanarParticle, MixtureLikelihoodShrugsOffAnOutlierTheGaussianOneFollows) {
  const auto density = Density(MixtureNoise());
  auto mixture = Particles(1, ParticleLikelihood::kMixture, density);
  auto gaussian = Particles(1, ParticleLikelihood::kGaussian, density);
  for (PlanarParticleFilter* f : {mixture.get(), gaussian.get()}) {
    f->Predict({3.5, 0.0}, 0.1);
    f->Update({0.35, 0.0});
    f->Update({30.0, 0.0});  // a stable-tail fix, 30 m ahead
  }
  EXPECT_LT(std::abs(mixture->Estimate().x() - 0.35), 0.5);
  // The Gaussian likelihood (sigma 1 m) puts all weight on the particles nearest 30 m.
  EXPECT_GT(gaussian->Estimate().x(), 1.0);
  EXPECT_GT(gaussian->resample_count(), 0);
}

TEST(PlanarParticle, SameSeedReplaysBitForBit) {
  const auto density = Density(MixtureNoise());
  auto a = Particles(7, ParticleLikelihood::kMixture, density);
  auto b = Particles(7, ParticleLikelihood::kMixture, density);
  auto c = Particles(8, ParticleLikelihood::kMixture, density);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector2d fix(0.35 * (k + 1) + (k % 7 == 0 ? 25.0 : 0.3), -0.2);
    for (PlanarParticleFilter* f : {a.get(), b.get(), c.get()}) {
      f->Predict({3.5, 0.1}, 0.1);
      f->Update(fix);
    }
    ASSERT_EQ(a->Estimate(), b->Estimate()) << "step " << k;
  }
  EXPECT_NE(a->Estimate(), c->Estimate());
}

TEST(PlanarParticle, RejectsBadOptionsNamingTheField) {
  PlanarParticleOptions options;
  options.particles = 0;
  EXPECT_NE(PlanarParticleFilter::Create(BicycleModel(), ControlNoise(), options, nullptr, std::mt19937_64(1))
                .status()
                .message()
                .find("particles"),
            std::string::npos);
  // The mixture likelihood without its density.
  EXPECT_NE(
      PlanarParticleFilter::Create(BicycleModel(), ControlNoise(), PlanarParticleOptions(), nullptr, std::mt19937_64(1))
          .status()
          .message()
          .find("mixture"),
      std::string::npos);
}

}  // namespace
}  // namespace localizer::engine::experiments
