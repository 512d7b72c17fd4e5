#include "engine/experiments/planar_particle.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "engine/experiments/experiment_random.h"
#include "engine/sim/invalid_value.h"

namespace localizer::engine::experiments {
namespace {

constexpr int kMaxParticles = 1000000;

// R with R R^T = P for a symmetric positive semi-definite P (negative eigenvalues from
// rounding clamped to 0).
Eigen::Matrix3d SemiDefiniteRoot(const Eigen::Matrix3d& p) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(0.5 * (p + p.transpose()));
  return eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
}

}  // namespace

Status PlanarParticleOptions::Validate() const {
  if (particles < 1 || particles > kMaxParticles) {
    return sim_detail::Invalid("particles", particles, "must be in [1, 1000000]");
  }
  if (!(gaussian_sigma_m > 0.0 && std::isfinite(gaussian_sigma_m))) {
    return sim_detail::Invalid("gaussian_sigma_m", gaussian_sigma_m, "must be positive and finite");
  }
  if (!(resample_ess_fraction >= 0.0 && resample_ess_fraction <= 1.0)) {
    return sim_detail::Invalid("resample_ess_fraction", resample_ess_fraction, "must be in [0, 1]");
  }
  return Status::Ok();
}

StatusOr<std::unique_ptr<PlanarParticleFilter>> PlanarParticleFilter::Create(
    const BicycleModel& model, const ControlNoise& control_noise, const PlanarParticleOptions& options,
    std::shared_ptr<const MixtureDensity> mixture, std::mt19937_64 engine) {
  LOCALIZER_RETURN_IF_ERROR(model.Validate());
  LOCALIZER_RETURN_IF_ERROR(control_noise.Validate());
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  if (options.likelihood == ParticleLikelihood::kMixture && mixture == nullptr) {
    return InvalidArgument("mixture is null; the mixture likelihood needs its density");
  }
  return std::unique_ptr<PlanarParticleFilter>(
      new PlanarParticleFilter(model, control_noise, options, std::move(mixture), engine));
}

PlanarParticleFilter::PlanarParticleFilter(const BicycleModel& model, const ControlNoise& control_noise,
                                           const PlanarParticleOptions& options,
                                           std::shared_ptr<const MixtureDensity> mixture, std::mt19937_64 engine)
    : model_(model),
      control_noise_(control_noise),
      options_(options),
      mixture_(std::move(mixture)),
      engine_(engine),
      particles_(options.particles, PlanarState::Zero()),
      scratch_(options.particles),
      weights_(options.particles, 1.0 / options.particles),
      log_weights_(options.particles, 0.0) {}

void PlanarParticleFilter::Initialise(const PlanarBelief& belief) {
  const Eigen::Matrix3d root = SemiDefiniteRoot(belief.covariance);
  for (PlanarState& s : particles_) {
    const Eigen::Vector3d z(StandardNormal(engine_), StandardNormal(engine_), StandardNormal(engine_));
    s = belief.mean + root * z;
  }
  std::fill(weights_.begin(), weights_.end(), 1.0 / options_.particles);
  std::fill(log_weights_.begin(), log_weights_.end(), 0.0);
  estimate_ = WeightedMean();
}

void PlanarParticleFilter::Predict(const BicycleControl& command, double dt_s) {
  for (PlanarState& s : particles_) {
    const double speed = command.speed_mps + control_noise_.speed_sigma_mps * StandardNormal(engine_);
    const double steering = command.steering_rad + control_noise_.steering_sigma_rad * StandardNormal(engine_);
    s = model_.Step(s, {speed, steering}, dt_s);
  }
  estimate_ = WeightedMean();
}

double PlanarParticleFilter::LogLikelihood(const Eigen::Vector2d& noise_m) const {
  if (options_.likelihood == ParticleLikelihood::kMixture) return mixture_->LogDensity(noise_m);
  return -0.5 * noise_m.squaredNorm() / (options_.gaussian_sigma_m * options_.gaussian_sigma_m);
}

void PlanarParticleFilter::Update(const Eigen::Vector2d& z_m) {
  const int n = options_.particles;
  double max_log = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    log_weights_[i] += LogLikelihood(z_m - particles_[i].head<2>());
    max_log = std::max(max_log, log_weights_[i]);
  }
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    log_weights_[i] -= max_log;  // keeps the largest at 0: no overflow, no drift
    weights_[i] = std::exp(log_weights_[i]);
    sum += weights_[i];
  }
  double sum_squares = 0.0;
  for (double& w : weights_) {
    w /= sum;
    sum_squares += w * w;
  }
  last_ess_ = 1.0 / sum_squares;
  estimate_ = WeightedMean();  // before resampling, which adds noise and no information
  if (last_ess_ < options_.resample_ess_fraction * n) ResampleSystematic();
}

PlanarState PlanarParticleFilter::WeightedMean() const {
  PlanarState mean = PlanarState::Zero();
  for (size_t i = 0; i < particles_.size(); ++i) mean += weights_[i] * particles_[i];
  return mean;
}

void PlanarParticleFilter::ResampleSystematic() {
  const int n = options_.particles;
  const double step = 1.0 / n;
  double pointer = OpenUniform(engine_) * step;
  double cumulative = weights_[0];
  int source = 0;
  for (int slot = 0; slot < n; ++slot) {
    while (pointer > cumulative && source < n - 1) cumulative += weights_[++source];
    scratch_[slot] = particles_[source];
    pointer += step;
  }
  particles_.swap(scratch_);
  std::fill(weights_.begin(), weights_.end(), step);
  std::fill(log_weights_.begin(), log_weights_.end(), 0.0);
  ++resample_count_;
}

}  // namespace localizer::engine::experiments
