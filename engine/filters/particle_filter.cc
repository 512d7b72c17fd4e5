#include "engine/filters/particle_filter.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

#include "engine/core/fast_math.h"
#include "engine/filters/particle_set.h"

namespace localizer::engine {

StatusOr<Likelihood> ParseLikelihood(const std::string& name) {
  if (name == "peak") return Likelihood::kPeak;
  if (name == "gcc") return Likelihood::kGcc;
  return InvalidArgument("likelihood '" + name + "' is not one of: peak, gcc");
}

const char* LikelihoodName(Likelihood l) { return l == Likelihood::kPeak ? "peak" : "gcc"; }

Status ParticleFilterOptions::Validate() const {
  if (particles < 16 || particles > (1 << 22)) {
    return InvalidArgument("particles must be in [16, 4194304], got " + std::to_string(particles));
  }
  if (!(accel_noise_mps2 >= 0.0) || !std::isfinite(accel_noise_mps2)) {
    return InvalidArgument("accel_noise_mps2 must be finite and >= 0, got " + std::to_string(accel_noise_mps2));
  }
  if (!(tdoa_sigma_s >= 0.0) || !std::isfinite(tdoa_sigma_s)) {
    return InvalidArgument("tdoa_sigma_s must be finite and >= 0 (0: adaptive), got " +
                           std::to_string(tdoa_sigma_s));
  }
  if (!(peak_dof > 0.0) || !std::isfinite(peak_dof)) {
    return InvalidArgument("peak_dof must be finite and > 0, got " + std::to_string(peak_dof));
  }
  if (!(gcc_sharpness > 0.0) || !std::isfinite(gcc_sharpness)) {
    return InvalidArgument("gcc_sharpness must be finite and > 0, got " + std::to_string(gcc_sharpness));
  }
  if (!(min_peak_snr >= 0.0) || !std::isfinite(min_peak_snr)) {
    return InvalidArgument("min_peak_snr must be finite and >= 0, got " + std::to_string(min_peak_snr));
  }
  if (!(resample_threshold >= 0.0 && resample_threshold <= 1.0)) {
    return InvalidArgument("resample_threshold must be in [0, 1], got " + std::to_string(resample_threshold));
  }
  if (!(kernel_scale >= 0.0 && kernel_scale <= 2.0)) {
    return InvalidArgument("kernel_scale must be in [0, 2], got " + std::to_string(kernel_scale));
  }
  return Status::Ok();
}

namespace {
// Adaptive TDOA noise (tdoa_sigma_s = 0): start at 0.1 sample, smooth over ~20 frames,
// keep within [0.01, 2] samples.
constexpr double kInitialSigmaSamples = 0.1;
constexpr double kSigmaSmoothing = 0.05;
constexpr double kMinSigmaSamples = 0.01;
constexpr double kMaxSigmaSamples = 2.0;
}  // namespace

struct ParticleFilter::Impl {
  Impl(const ArrayGeometry& a, const ParticleFilterOptions& o) : array(a), options(o), set(a, o) {}
  ArrayGeometry array;
  ParticleFilterOptions options;
  ParticleSet set;
  bool initialised = false;
  double ess = 0.0;
  std::vector<double> sigmas_s;  // TDOA noise std per pair (empty until the first update)
  std::vector<InnovationMoments> innovations;
  std::vector<int> used;  // per pair: 1 when its peak_snr passes min_peak_snr
};

ParticleFilter::ParticleFilter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ParticleFilter::~ParticleFilter() = default;

StatusOr<std::unique_ptr<ParticleFilter>> ParticleFilter::Create(const ArrayGeometry& array,
                                                                 const ParticleFilterOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  return std::unique_ptr<ParticleFilter>(new ParticleFilter(std::make_unique<Impl>(array, options)));
}

bool ParticleFilter::initialised() const { return impl_->initialised; }
int ParticleFilter::particle_count() const { return impl_->options.particles; }
double ParticleFilter::ess() const { return impl_->ess; }
double ParticleFilter::tdoa_sigma_s() const {
  double sum_s2 = 0.0;
  for (double sigma_s : impl_->sigmas_s) sum_s2 += sigma_s * sigma_s;
  return impl_->sigmas_s.empty() ? 0.0 : std::sqrt(sum_s2 / static_cast<double>(impl_->sigmas_s.size()));
}

Status ParticleFilter::Initialise(const TrackState& belief) {
  if (!belief.mean.allFinite() || !belief.covariance.allFinite()) {
    return InvalidArgument("initial belief has a non-finite mean or covariance");
  }
  // A square root that tolerates semi-definite covariances: V sqrt(max(L, 0)).
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(0.5 * (belief.covariance + belief.covariance.transpose()));
  if (eig.eigenvalues().minCoeff() < -1e-9 * std::max(1.0, eig.eigenvalues().maxCoeff())) {
    return InvalidArgument("initial covariance is not positive semi-definite");
  }
  const Mat6 root = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  impl_->set.SampleGaussian(belief.mean, root);
  impl_->initialised = true;
  impl_->ess = impl_->options.particles;
  return Status::Ok();
}

Status ParticleFilter::InitialiseRegion(const Vec3& min_m, const Vec3& max_m, double speed_sigma_mps) {
  if (!min_m.allFinite() || !max_m.allFinite() || (max_m - min_m).minCoeff() < 0.0 ||
      !(speed_sigma_mps >= 0.0)) {
    return InvalidArgument("initial region must be a finite box with min <= max and speed sigma >= 0");
  }
  impl_->set.SampleUniformBox(min_m, max_m, speed_sigma_mps);
  impl_->initialised = true;
  impl_->ess = impl_->options.particles;
  return Status::Ok();
}

void ParticleFilter::Predict(double dt_s) {
  if (!impl_->initialised || !(dt_s > 0.0)) return;
  impl_->set.Predict(dt_s, impl_->options.accel_noise_mps2);
}

StatusOr<UpdateReport> ParticleFilter::Update(const Measurement& m) {
  if (!impl_->initialised) return FailedPrecondition("particle filter updated before initialisation");
  if (static_cast<int>(m.pairs.size()) != impl_->array.pair_count()) {
    return InvalidArgument("measurement has " + std::to_string(m.pairs.size()) + " pairs; the array has " +
                           std::to_string(impl_->array.pair_count()));
  }
  if (!(m.sample_rate_hz > 0.0)) return InvalidArgument("measurement sample_rate_hz must be > 0");
  const ParticleFilterOptions& o = impl_->options;
  Impl& s = *impl_;
  if (s.sigmas_s.size() != m.pairs.size()) {
    s.sigmas_s.assign(m.pairs.size(),
                      o.tdoa_sigma_s > 0.0 ? o.tdoa_sigma_s : kInitialSigmaSamples / m.sample_rate_hz);
  }
  UpdateReport report;
  s.used.resize(m.pairs.size());
  for (size_t p = 0; p < m.pairs.size(); ++p) {
    s.used[p] = m.pairs[p].peak_snr >= o.min_peak_snr ? 1 : 0;
    report.pair_count += s.used[p];
  }
  if (report.pair_count == 0) {  // no pair heard a source: nothing to condition on
    report.ess = impl_->ess;
    report.tdoa_sigma_s = tdoa_sigma_s();
    return report;
  }
  s.set.Weigh(m, s.used, o.likelihood, s.sigmas_s, o.peak_dof, o.gcc_sharpness, &s.innovations);
  double mean_var_s2 = 0.0;
  for (size_t p = 0; p < s.innovations.size(); ++p) {
    double& sigma_s = s.sigmas_s[p];
    mean_var_s2 += sigma_s * sigma_s / static_cast<double>(s.innovations.size());
    if (!s.used[p]) continue;
    const InnovationMoments& in = s.innovations[p];
    report.nis += in.mean_s * in.mean_s / (sigma_s * sigma_s + in.predicted_var_s2);
    if (o.tdoa_sigma_s == 0.0) {  // innovation-based adaptive estimate (Mehra 1972), per pair
      const double excess_s2 = std::max(0.0, in.mean_s * in.mean_s - in.predicted_var_s2);
      const double var_s2 = (1.0 - kSigmaSmoothing) * sigma_s * sigma_s + kSigmaSmoothing * excess_s2;
      sigma_s = std::clamp(std::sqrt(var_s2), kMinSigmaSamples / m.sample_rate_hz,
                           kMaxSigmaSamples / m.sample_rate_hz);
    }
  }
  report.tdoa_sigma_s = std::sqrt(mean_var_s2);
  report.ess = impl_->set.NormaliseWeights();
  impl_->ess = report.ess;
  if (report.ess < o.resample_threshold * o.particles) impl_->set.ResampleSystematic(o.kernel_scale);
  return report;
}

TrackState ParticleFilter::State() const { return impl_->set.MeanAndCovariance(); }

}  // namespace localizer::engine
