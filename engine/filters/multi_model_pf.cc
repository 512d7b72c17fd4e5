#include "engine/filters/multi_model_pf.h"

#include <cmath>
#include <limits>
#include <set>
#include <string>

#include "engine/core/fast_math.h"
#include "engine/filters/model_switching.h"
#include "engine/filters/pair_noise.h"
#include "engine/filters/particle_set.h"

namespace localizer::engine {
namespace {
constexpr int kMaxModels = 16;  // labels are bytes; Validate caps K here
}  // namespace

std::vector<ParticleMotion> DefaultParticleMotions(double accel_noise_mps2, double turn_rate_radps) {
  return {{"cv", accel_noise_mps2, 0.0},
          {"cv-manoeuvre", 4.0 * accel_noise_mps2, 0.0},
          {"ct-left", accel_noise_mps2, turn_rate_radps},
          {"ct-right", accel_noise_mps2, -turn_rate_radps}};
}

Status MultiModelPfOptions::Validate() const {
  LOCALIZER_RETURN_IF_ERROR(particle.Validate());
  if (models.size() > static_cast<size_t>(kMaxModels)) {
    return InvalidArgument("models has " + std::to_string(models.size()) + " entries; at most " +
                           std::to_string(kMaxModels));
  }
  std::set<std::string> names;
  for (const ParticleMotion& m : models) {
    if (m.name.empty() || !names.insert(m.name).second) {
      return InvalidArgument("models: names must be non-empty and unique, got '" + m.name + "' twice or empty");
    }
    if (!(m.accel_noise_mps2 >= 0.0) || !std::isfinite(m.accel_noise_mps2)) {
      return InvalidArgument("models[" + m.name + "].accel_noise_mps2 must be finite and >= 0");
    }
    if (!std::isfinite(m.turn_rate_radps))
      return InvalidArgument("models[" + m.name + "].turn_rate_radps must be finite");
  }
  return ValidateStayProbability(stay_probability, "stay_probability");
}

struct MultiModelParticleFilter::Impl {
  Impl(const ArrayGeometry& a, const MultiModelPfOptions& o)
      : array(a), options(o), base(a, o.particle), noise(o.particle.tdoa_sigma_s) {
    if (options.models.empty()) options.models = DefaultParticleMotions(o.particle.accel_noise_mps2);
    const int k = count();
    for (int i = 0; i < k; ++i) {
      sets.push_back(std::make_unique<ParticleSet>(a, o.particle));
      candidates.push_back(sets.back().get());
    }
    pi = SwitchingMatrix(k, options.stay_probability);
    log_pi = pi.array().log().cwiseMax(-1e30).matrix();  // log 0 -> a finite "never"
    mu = Eigen::VectorXd::Constant(k, 1.0 / k);
    const int n = o.particle.particles;
    label.assign(n, 0);
    prior_label.assign(n, 0);
    innovations.resize(k);
    // Scratch: K N log-alphas (also 2 N of pick scratch, hence the max), K N alphas.
    log_alpha.assign(static_cast<size_t>(n) * std::max(k, 2), 0.0f);
    alpha.assign(static_cast<size_t>(n) * k, 0.0f);
    log_weight.assign(n, 0.0f);
  }
  int count() const { return static_cast<int>(options.models.size()); }
  int particles() const { return options.particle.particles; }
  uint32_t NextKey() { return base.NextKey(); }
  void Restart();
  // Label masses sum_i w_i [m_i = k], normalised.
  Eigen::VectorXd LabelMasses(const std::vector<uint8_t>& labels) const;
  // Draws particle i's hypothesis from pi(prior_label_i, .) into label (the bootstrap pick).
  void DrawLabelsFromPrior();
  // The per-particle pick of Update (see the header); returns the ESS.
  double PickByLikelihood();
  void ResampleIfNeeded(double ess);

  ArrayGeometry array;
  MultiModelPfOptions options;
  ParticleSet base;                                // the cloud the estimate is read from
  std::vector<std::unique_ptr<ParticleSet>> sets;  // one prediction per hypothesis
  std::vector<const ParticleSet*> candidates;      // = sets
  PairNoise noise;                                 // shared: every cloud is weighed alike
  Eigen::MatrixXd pi, log_pi;
  Eigen::VectorXd mu;
  std::vector<uint8_t> label, prior_label;  // hypothesis kept per particle; before Predict
  std::vector<std::vector<InnovationMoments>> innovations;
  std::vector<float> log_alpha, alpha, log_weight;  // scratch, K N and N
  bool predicted = false;                           // the K clouds hold predictions not yet weighed
  bool initialised = false;
  double ess = 0.0;
};

void MultiModelParticleFilter::Impl::Restart() {
  for (int i = 0; i < particles(); ++i) label[i] = static_cast<uint8_t>(i % count());
  initialised = true;
  predicted = false;
  ess = particles();
  mu = LabelMasses(label);
}

Eigen::VectorXd MultiModelParticleFilter::Impl::LabelMasses(const std::vector<uint8_t>& labels) const {
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(count());
  const AlignedVector<float>& w = base.weights();
  for (int i = 0; i < particles(); ++i) mass(labels[i]) += w[i];
  return mass / mass.sum();
}

void MultiModelParticleFilter::Impl::DrawLabelsFromPrior() {
  const uint32_t key = NextKey();
  const int k = count();
  const double stay = options.stay_probability;
  for (int i = 0; i < particles(); ++i) {
    const double u = UniformFromCounter(key, static_cast<uint32_t>(i));
    if (k == 1 || u < stay) {
      label[i] = prior_label[i];
      continue;
    }
    // Another hypothesis, uniformly: the (K - 1) others in order, skipping the current one.
    int other = std::min(k - 2, static_cast<int>((u - stay) / (1.0 - stay) * (k - 1)));
    if (other >= prior_label[i]) ++other;
    label[i] = static_cast<uint8_t>(other);
  }
}

double MultiModelParticleFilter::Impl::PickByLikelihood() {
  const int n = particles(), k = count();
  // log alpha_ik = (log w_i + log l_ik) + log pi(m_i, k): each set's log-weights already
  // hold the first two terms (prior weights copied at Predict, then Weigh). Column-wise
  // loops over i, so that they vectorise.
  float top = -std::numeric_limits<float>::infinity();
  for (int j = 0; j < k; ++j) {
    const float* __restrict logw = sets[j]->log_weights().data();
    float* __restrict la = log_alpha.data() + static_cast<size_t>(j) * n;
    float log_pi_j[kMaxModels];
    for (int from = 0; from < k; ++from) log_pi_j[from] = static_cast<float>(log_pi(from, j));
    const uint8_t* __restrict from_label = prior_label.data();
#pragma omp simd reduction(max : top)
    for (int i = 0; i < n; ++i) {
      la[i] = logw[i] + log_pi_j[from_label[i]];
      top = std::max(top, la[i]);
    }
  }
  // alpha relative to the cloud's largest; per particle the running sums over hypotheses.
  float* __restrict sum = log_weight.data();  // the sums first, their logs at the end
  std::fill(log_weight.begin(), log_weight.end(), 0.0f);
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(k);
  for (int j = 0; j < k; ++j) {
    const float* __restrict la = log_alpha.data() + static_cast<size_t>(j) * n;
    float* __restrict a = alpha.data() + static_cast<size_t>(j) * n;
    float column = 0.0f;
#pragma omp simd reduction(+ : column)
    for (int i = 0; i < n; ++i) {
      a[i] = FastExp(la[i] - top);
      sum[i] += a[i];
      column += a[i];
    }
    mass(j) = column;
  }
  // Keep candidate j with probability alpha_ij / sum_j alpha_ij: u_i in (0, sum_i), the
  // pick is how many of the cumulative sums u_i passes.
  const uint32_t key = NextKey();
  std::vector<float>& u = log_alpha;  // reused: the log-alphas are no longer needed
  uint8_t* __restrict pick = label.data();
#pragma omp simd
  for (int i = 0; i < n; ++i) {
    u[i] = UniformFromCounter(key, static_cast<uint32_t>(i)) * sum[i];
    pick[i] = 0;
  }
  std::fill(u.begin() + n, u.begin() + 2 * n, 0.0f);
  float* __restrict acc = u.data() + n;
  for (int j = 0; j < k - 1; ++j) {
    const float* __restrict a = alpha.data() + static_cast<size_t>(j) * n;
#pragma omp simd
    for (int i = 0; i < n; ++i) {
      acc[i] += a[i];
      pick[i] = static_cast<uint8_t>(pick[i] + (u[i] >= acc[i] ? 1 : 0));
    }
  }
#pragma omp simd
  for (int i = 0; i < n; ++i) sum[i] = top + FastLog(sum[i]);  // the new log-weights
  mu = mass / mass.sum();
  return base.TakeParticles(candidates, label, log_weight);
}

void MultiModelParticleFilter::Impl::ResampleIfNeeded(double ess_now) {
  ess = ess_now;
  const ParticleFilterOptions& o = options.particle;
  if (ess_now >= o.resample_threshold * o.particles) return;
  base.ResampleSystematic(o.kernel_scale);
  const AlignedVector<int>& index = base.resample_index();
  prior_label = label;  // scratch: the labels before the copies
  for (int m = 0; m < particles(); ++m) label[m] = prior_label[index[m]];
}

MultiModelParticleFilter::MultiModelParticleFilter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
MultiModelParticleFilter::~MultiModelParticleFilter() = default;

StatusOr<std::unique_ptr<MultiModelParticleFilter>> MultiModelParticleFilter::Create(
    const ArrayGeometry& array, const MultiModelPfOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  return std::unique_ptr<MultiModelParticleFilter>(
      new MultiModelParticleFilter(std::make_unique<Impl>(array, options)));
}

bool MultiModelParticleFilter::initialised() const { return impl_->initialised; }
int MultiModelParticleFilter::model_count() const { return impl_->count(); }

Status MultiModelParticleFilter::Initialise(const TrackState& belief) {
  const auto root = BeliefRoot(belief);
  if (!root.ok()) return root.status();
  impl_->base.SampleGaussian(belief.mean, *root);
  impl_->Restart();
  return Status::Ok();
}

Status MultiModelParticleFilter::InitialiseRegion(const Vec3& min_m, const Vec3& max_m, double speed_sigma_mps) {
  LOCALIZER_RETURN_IF_ERROR(ValidateRegion(min_m, max_m, speed_sigma_mps));
  impl_->base.SampleUniformBox(min_m, max_m, speed_sigma_mps);
  impl_->Restart();
  return Status::Ok();
}

void MultiModelParticleFilter::Predict(double dt_s) {
  Impl& s = *impl_;
  if (!s.initialised || !(dt_s > 0.0)) return;
  const uint32_t key = s.NextKey();  // one noise draw for every hypothesis
  for (int k = 0; k < s.count(); ++k) {
    const ParticleMotion& m = s.options.models[k];
    s.sets[k]->CopyCloudFrom(s.base);
    s.sets[k]->PredictTurn(dt_s, m.turn_rate_radps, m.accel_noise_mps2, key);
  }
  // Two predicts in a row: the second starts from the first's bootstrap pick.
  s.prior_label = s.label;
  s.DrawLabelsFromPrior();
  (void)s.base.TakeParticles(s.candidates, s.label, s.base.log_weights());
  // mu_k = sum_i w_i pi(m_i, k) = (pi^T M)_k, M the weight mass of each prior label.
  s.mu = s.pi.transpose() * s.LabelMasses(s.prior_label);
  s.predicted = true;
}

StatusOr<UpdateReport> MultiModelParticleFilter::Update(const Measurement& m) {
  Impl& s = *impl_;
  if (!s.initialised) return FailedPrecondition("multiple-model particle filter updated before initialisation");
  if (static_cast<int>(m.pairs.size()) != s.array.pair_count()) {
    return InvalidArgument("measurement has " + std::to_string(m.pairs.size()) + " pairs; the array has " +
                           std::to_string(s.array.pair_count()));
  }
  if (!(m.sample_rate_hz > 0.0)) return InvalidArgument("measurement sample_rate_hz must be > 0");
  const ParticleFilterOptions& o = s.options.particle;
  UpdateReport report;
  report.pair_count = s.noise.Select(m, o.min_peak_snr);
  if (report.pair_count == 0) {  // nothing to weigh: the bootstrap prediction stands
    report.ess = s.ess;
    report.tdoa_sigma_s = s.noise.rms_sigma_s();
    return report;
  }
  double ess = 0.0;
  if (s.predicted) {
    Eigen::Index likeliest = 0;
    s.mu.maxCoeff(&likeliest);  // before the update
    for (int k = 0; k < s.count(); ++k) {
      s.sets[k]->Weigh(m, s.noise.used(), o.likelihood, s.noise.sigmas_s(), o.peak_dof, o.gcc_sharpness,
                       &s.innovations[k]);
    }
    s.noise.Finish(s.innovations[likeliest], m.sample_rate_hz, &report);
    ess = s.PickByLikelihood();
  } else {  // the first frame after a restart: one cloud, labels as they are
    s.base.Weigh(m, s.noise.used(), o.likelihood, s.noise.sigmas_s(), o.peak_dof, o.gcc_sharpness, &s.innovations[0]);
    s.noise.Finish(s.innovations[0], m.sample_rate_hz, &report);
    ess = s.base.NormaliseWeights();
    s.mu = s.LabelMasses(s.label);
  }
  s.predicted = false;
  report.ess = ess;
  s.ResampleIfNeeded(ess);
  return report;
}

TrackState MultiModelParticleFilter::State() const { return impl_->base.MeanAndCovariance(); }

std::vector<ModelProbability> MultiModelParticleFilter::ModelProbabilities() const {
  std::vector<ModelProbability> out;
  if (!impl_->initialised) return out;
  for (int k = 0; k < impl_->count(); ++k) out.push_back({impl_->options.models[k].name, impl_->mu(k)});
  return out;
}

}  // namespace localizer::engine

namespace localizer::engine {

Status MultiModelParticleFilter::SetArray(const ArrayGeometry& array) {
  LOCALIZER_RETURN_IF_ERROR(ValidateMovedArray(impl_->array, array));
  impl_->array = array;
  impl_->base.SetSensors(array);
  for (auto& set : impl_->sets) set->SetSensors(array);
  return Status::Ok();
}

}  // namespace localizer::engine
