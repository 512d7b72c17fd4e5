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
  if (name == "mixture") return Likelihood::kMixture;
  return InvalidArgument("likelihood '" + name + "' is not one of: peak, gcc, mixture");
}

const char* LikelihoodName(Likelihood l) {
  return l == Likelihood::kPeak ? "peak" : l == Likelihood::kGcc ? "gcc" : "mixture";
}

Status ParticleFilterOptions::Validate() const {
  if (particles < 16 || particles > (1 << 22)) {
    return InvalidArgument("particles must be in [16, 4194304], got " + std::to_string(particles));
  }
  if (!(accel_noise_mps2 >= 0.0) || !std::isfinite(accel_noise_mps2)) {
    return InvalidArgument("accel_noise_mps2 must be finite and >= 0, got " + std::to_string(accel_noise_mps2));
  }
  if (!(manoeuvre_share >= 0.0 && manoeuvre_share < 1.0)) {
    return InvalidArgument("manoeuvre_share must be in [0, 1), got " + std::to_string(manoeuvre_share));
  }
  if (!(manoeuvre_scale >= 1.0) || !std::isfinite(manoeuvre_scale)) {
    return InvalidArgument("manoeuvre_scale must be finite and >= 1, got " + std::to_string(manoeuvre_scale));
  }
  if (!(accel_level_floor >= 1e-6 && accel_level_floor <= accel_level_ceiling && accel_level_ceiling <= 100.0)) {
    return InvalidArgument(
        "accel_level_floor and accel_level_ceiling must satisfy 1e-6 <= floor <= ceiling <= 100, got " +
        std::to_string(accel_level_floor) + " and " + std::to_string(accel_level_ceiling));
  }
  if (!(accel_level_switch_hz >= 0.0 && accel_level_switch_hz <= 1000.0)) {
    return InvalidArgument("accel_level_switch_hz must be in [0, 1000], got " + std::to_string(accel_level_switch_hz));
  }
  if (!(tdoa_sigma_s >= 0.0) || !std::isfinite(tdoa_sigma_s)) {
    return InvalidArgument("tdoa_sigma_s must be finite and >= 0 (0: adaptive), got " + std::to_string(tdoa_sigma_s));
  }
  if (!(outlier_probability >= 0.0 && outlier_probability < 1.0)) {
    return InvalidArgument("outlier_probability must be in [0, 1), got " + std::to_string(outlier_probability));
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
  if (tempered_updates < 0 || tempered_updates > 100) {
    return InvalidArgument("tempered_updates must be in [0, 100], got " + std::to_string(tempered_updates));
  }
  if (!(velocity_time_constant_s >= 0.0 && velocity_time_constant_s <= 1e6)) {
    return InvalidArgument("velocity_time_constant_s must be in [0, 1e6], got " +
                           std::to_string(velocity_time_constant_s));
  }
  if (!(tempering_ess_fraction >= 0.0 && tempering_ess_fraction <= 1.0)) {
    return InvalidArgument("tempering_ess_fraction must be in [0, 1], got " + std::to_string(tempering_ess_fraction));
  }
  if (!(turn_rate_max_radps >= 0.0 && turn_rate_max_radps <= 5.0)) {
    return InvalidArgument("turn_rate_max_radps must be in [0, 5], got " + std::to_string(turn_rate_max_radps));
  }
  if (turn_rate_max_radps > 0.0 && velocity_time_constant_s > 0.0) {
    return InvalidArgument(
        "turn rates need constant velocity: velocity_time_constant_s > 0 needs turn_rate_max_radps = 0");
  }
  if (!(speed_change_max_mps2 >= 0.0 && speed_change_max_mps2 <= 20.0)) {
    return InvalidArgument("speed_change_max_mps2 must be in [0, 20], got " + std::to_string(speed_change_max_mps2));
  }
  if (speed_change_max_mps2 > 0.0 && velocity_time_constant_s > 0.0) {
    return InvalidArgument(
        "speed changes need constant velocity: velocity_time_constant_s > 0 needs speed_change_max_mps2 = 0");
  }
  if (!(motion_blur >= 0.0 && motion_blur <= 1.0)) {
    return InvalidArgument("motion_blur must be in [0, 1], got " + std::to_string(motion_blur));
  }
  if (!(kernel_scale >= 0.0 && kernel_scale <= 2.0)) {
    return InvalidArgument("kernel_scale must be in [0, 2], got " + std::to_string(kernel_scale));
  }
  return Status::Ok();
}

struct ParticleFilter::Impl {
  Impl(const ArrayGeometry& a, const ParticleFilterOptions& o)
      : array(a), options(o), set(a, o), noise(o.tdoa_sigma_s) {
    set.SetManoeuvre(o.manoeuvre_share, o.manoeuvre_scale);
    set.SetAccelLevels(o.accel_level_floor, o.accel_level_ceiling, o.accel_level_switch_hz);
    set.SetTurnRates(o.turn_rate_max_radps, o.accel_level_switch_hz);
    set.SetSpeedChanges(o.speed_change_max_mps2, o.accel_level_switch_hz);
  }
  ArrayGeometry array;
  ParticleFilterOptions options;
  ParticleSet set;
  bool initialised = false;
  double ess = 0.0;
  PairNoise noise;  // pairs used and their TDOA noise std
  std::vector<InnovationMoments> innovations;
  std::vector<InnovationMoments> later_innovations;  // of a tempered update's later stages
  int tempered_updates_left = 0;                     // updates still applied progressively after a (re)start
};

constexpr int kTemperedStages = 4;
// Adaptive tempering (AdaptiveUpdate): at most this many stages per update, each keeping
// the ESS near kStageEssFraction x N and taking at least kMinStageShare of what is left.
constexpr int kAdaptiveStages = 6;
// The first updates after a (re)start with one label: as many stages as a fix with an
// unknown velocity needs (particle_start_test: 6, 12 and 24 within 2x of each other).
constexpr int kStartStages = 12;
constexpr double kStageEssFraction = 0.2;
constexpr float kMinStageShare = 1.0f / 16.0f;
constexpr int kBisectionSteps = 8;

ParticleFilter::ParticleFilter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ParticleFilter::~ParticleFilter() = default;

StatusOr<std::unique_ptr<ParticleFilter>> ParticleFilter::Create(const ArrayGeometry& array,
                                                                 const ParticleFilterOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  return std::unique_ptr<ParticleFilter>(new ParticleFilter(std::make_unique<Impl>(array, options)));
}

bool ParticleFilter::initialised() const { return impl_->initialised; }
double ParticleFilter::ess() const { return impl_->ess; }
double ParticleFilter::tdoa_sigma_s() const { return impl_->noise.rms_sigma_s(); }

StatusOr<Mat6> BeliefRoot(const TrackState& belief) {
  if (!belief.mean.allFinite() || !belief.covariance.allFinite()) {
    return InvalidArgument("initial belief has a non-finite mean or covariance");
  }
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(0.5 * (belief.covariance + belief.covariance.transpose()));
  if (eig.eigenvalues().minCoeff() < -1e-9 * std::max(1.0, eig.eigenvalues().maxCoeff())) {
    return InvalidArgument("initial covariance is not positive semi-definite");
  }
  return Mat6(eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal());
}

Status ParticleFilter::Initialise(const TrackState& belief) {
  const auto root = BeliefRoot(belief);
  if (!root.ok()) return root.status();
  impl_->set.SampleGaussian(belief.mean, *root);
  impl_->initialised = true;
  impl_->ess = impl_->options.particles;
  impl_->tempered_updates_left = impl_->options.tempered_updates;
  return Status::Ok();
}

Status ParticleFilter::InitialiseRegion(const Vec3& min_m, const Vec3& max_m, double speed_sigma_mps) {
  LOCALIZER_RETURN_IF_ERROR(ValidateRegion(min_m, max_m, speed_sigma_mps));
  impl_->set.SampleUniformBox(min_m, max_m, speed_sigma_mps);
  impl_->initialised = true;
  impl_->ess = impl_->options.particles;
  impl_->tempered_updates_left = impl_->options.tempered_updates;
  return Status::Ok();
}

Status ParticleFilter::InitialiseMixture(const std::vector<WeightedBelief>& components) {
  if (components.empty()) return InvalidArgument("mixture initialisation needs at least one component");
  std::vector<ParticleSet::Component> parts;
  for (const WeightedBelief& c : components) {
    if (!(c.weight > 0.0) || !std::isfinite(c.weight)) return InvalidArgument("mixture weights must be finite and > 0");
    const auto root = BeliefRoot(c.belief);
    if (!root.ok()) return root.status();
    parts.push_back({c.weight, c.belief.mean, *root});
  }
  if (parts.size() == 1) {
    impl_->set.SampleGaussian(parts[0].mean, parts[0].root);
  } else {
    impl_->set.SampleMixture(parts);
  }
  impl_->initialised = true;
  impl_->ess = impl_->options.particles;
  impl_->tempered_updates_left = impl_->options.tempered_updates;
  return Status::Ok();
}

std::vector<WeightedBelief> ParticleFilter::Hypotheses() const { return impl_->set.Modes(1e-3); }

void ParticleFilter::SetBounds(const Vec3& min_m, const Vec3& max_m) { impl_->set.SetBounds(min_m, max_m); }

void ParticleFilter::Predict(double dt_s) {
  if (!impl_->initialised || !(dt_s > 0.0)) return;
  impl_->set.Predict(dt_s, impl_->options.accel_noise_mps2, impl_->options.velocity_time_constant_s);
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
  UpdateReport report;
  report.pair_count = s.noise.Select(m, o.min_peak_snr);
  if (report.pair_count == 0) {  // no pair heard a source: nothing to condition on
    report.ess = impl_->ess;
    report.tdoa_sigma_s = tdoa_sigma_s();
    return report;
  }
  // Progressive correction for the first updates after a (re)start: the likelihood is
  // applied in kTemperedStages steps of likelihood^(1/stages), each followed by
  // resampling and the kernel move, so a prior far wider than the likelihood
  // (a fix's position and an unknown velocity against TDOAs precise to centimetres) is
  // narrowed gradually instead of collapsing onto the few particles that happened to land
  // near the peak (Oudjane & Musso 2000). When even the first step would collapse the cloud
  // (ESS below tempering_ess_fraction x N) and one label lives, the update is taken back
  // and goes in as many ESS-chosen stages as it needs instead (AdaptiveUpdate, up to
  // kStartStages): one 0.17-s hop after a fix whose velocity is unknown
  // (init_speed_sigma_mps) the cloud is decimetres wide against TDOAs that fix the position
  // to a fraction of a millimetre, and the equal steps left the posterior on particles that
  // matched in direction and missed in range (particle_start_test: 450-2400 x the CRLB after
  // the second update in 2 of 3 seeds, 2.6-22 x with ESS-chosen stages). Starts that do not
  // collapse keep the equal steps (the filter bounds' random-acceleration target: 1.36 x its
  // bound over 16 seeds with them, 1.90 with ESS-chosen stages at every start).
  if (s.tempered_updates_left == 0) {
    report.ess = AdaptiveUpdate(m, &report.likelihood_stages, kAdaptiveStages);
  } else {
    // The first updates after a (re)start: where a label's cloud would collapse on the fix
    // this frame gives near it, half its particles are redrawn around that fix, weighted so
    // the label keeps its predicted density (ProposeLocalFixes, particle_set.h).
    // Those particles need no stages to reach the likelihood, and equal stages would
    // scatter them: each resampling moves every particle by a kernel sized by the whole
    // label's spread, still decimetres while the tempered likelihood keeps the prior's
    // particles alive. So such an update goes in whole (or in ESS-chosen stages).
    // particle_proposal_test: a talker inside a 0.25 m tetrahedron, restarted on both exact
    // solutions, 0.64-0.97 x the CRLB (the far solution won within a hop before);
    // particle_start_test: 1.5-83 x after the second update.
    --s.tempered_updates_left;
    if (ProposeLocalFixes(&s.set, s.array, m, s.noise.used(), s.noise.sigmas_s(), o.tempering_ess_fraction) > 0) {
      report.ess = AdaptiveUpdate(m, &report.likelihood_stages, kStartStages);
    } else {
      report.likelihood_stages = kTemperedStages;
      const float step = 1.0f / static_cast<float>(kTemperedStages);
      for (int stage = 0; stage < kTemperedStages; ++stage) {
        std::vector<InnovationMoments>* innovations = stage == 0 ? &s.innovations : &s.later_innovations;
        s.set.Weigh(m, s.noise.used(), o.likelihood, s.noise.sigmas_s(), o.peak_dof, o.gcc_sharpness, innovations,
                    step);
        report.ess = s.set.NormaliseWeights();
        if (stage == 0 && report.ess < o.tempering_ess_fraction * o.particles && s.set.labels() <= 1) {
          s.set.Untemper(step);  // back to the prior's weights
          report.ess = AdaptiveUpdate(m, &report.likelihood_stages, kStartStages);
          break;
        }
        const bool last = stage + 1 == kTemperedStages;
        if (!last || report.ess < o.resample_threshold * o.particles) s.set.ResampleSystematic(o.kernel_scale);
      }
    }
  }
  s.noise.Finish(s.innovations, m.sample_rate_hz, &report);  // the prior's innovations
  impl_->ess = report.ess;
  return report;
}

// One update, split only when it would collapse the cloud: the whole likelihood is applied;
// if the ESS falls below tempering_ess_fraction x N, the largest share b of it that keeps
// the ESS at kStageEssFraction x N is kept (found by bisection on the log-likelihoods
// Weigh left), the cloud is resampled and moved, and what is left of the likelihood is
// applied again to the moved particles, up to max_stages times. A likelihood far
// narrower than the predicted cloud (a near source on a small array with a sharp front end:
// millimetre fixes against centimetres of white-acceleration spread) would otherwise land on
// the few particles that happen to lie near its peak, or on none, while a wider mode (the
// far exact solution of a 4-sensor array, whose TDOAs barely change along range) keeps
// many; the wide mode then wins on sampling luck, not evidence.
double ParticleFilter::AdaptiveUpdate(const Measurement& m, int* stages, int max_stages) {
  Impl& s = *impl_;
  const ParticleFilterOptions& o = s.options;
  const double n = o.particles;
  float left = 1.0f;
  double ess = 0.0;
  for (int stage = 0;; ++stage) {
    std::vector<InnovationMoments>* innovations = stage == 0 ? &s.innovations : &s.later_innovations;
    s.set.Weigh(m, s.noise.used(), o.likelihood, s.noise.sigmas_s(), o.peak_dof, o.gcc_sharpness, innovations, left);
    ess = s.set.NormaliseWeights();
    *stages = stage + 1;
    // While several labels live, resampling keeps each contender's share (particle_set.h)
    // and more resamplings per frame would wear the weaker one down: one stage then.
    const bool split = ess < o.tempering_ess_fraction * n && stage + 1 < max_stages && s.set.labels() <= 1;
    if (!split) {
      if (ess < o.resample_threshold * n) s.set.ResampleSystematic(o.kernel_scale);
      return ess;
    }
    float lo = 0.0f, hi = left;  // ESS(lo) >= target > ESS(hi)
    for (int k = 0; k < kBisectionSteps; ++k) {
      const float mid = 0.5f * (lo + hi);
      (s.set.EssIfUntempered(left - mid) >= kStageEssFraction * n ? lo : hi) = mid;
    }
    const float kept = std::max(lo, left * kMinStageShare);
    s.set.Untemper(left - kept);
    s.set.ResampleSystematic(o.kernel_scale);
    left -= kept;
  }
}

TrackState ParticleFilter::State() const { return impl_->set.MeanAndCovariance(); }

}  // namespace localizer::engine

namespace localizer::engine {

Status ParticleFilter::SetArray(const ArrayGeometry& array) {
  LOCALIZER_RETURN_IF_ERROR(ValidateMovedArray(impl_->array, array));
  impl_->array = array;
  impl_->set.SetSensors(array);
  return Status::Ok();
}

}  // namespace localizer::engine
