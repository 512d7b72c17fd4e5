#include "engine/filters/imm_filter.h"

#include <algorithm>
#include <set>
#include <sstream>
#include <string>

#include "engine/filters/model_switching.h"

namespace localizer::engine {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// A mode's estimate in another mode's state space (see the header's mixing rule).
struct Embedded {
  VectorXd x;
  MatrixXd p;
};

Embedded Embed(const KalmanFilter& from, const KalmanFilter& to) {
  if (std::string(from.motion_model_name()) == to.motion_model_name()) return {from.mean(), from.covariance()};
  const int n = to.state_dim(), extra = n - 6;
  Embedded e{to.mean(), MatrixXd::Zero(n, n)};
  e.x.head<6>() = from.mean().head<6>();
  e.p.topLeftCorner<6, 6>() = from.covariance().topLeftCorner<6, 6>();
  if (extra > 0) e.p.bottomRightCorner(extra, extra) = to.covariance().bottomRightCorner(extra, extra);
  return e;
}

}  // namespace

StatusOr<std::vector<MotionModelKind>> ParseImmModes(const std::string& list, const std::string& field) {
  std::vector<std::string> names;
  std::stringstream in(list);
  std::string name;
  while (std::getline(in, name, ',')) {
    if (name.empty()) return InvalidArgument(field + " '" + list + "' has an empty entry");
    names.push_back(name);
  }
  if (names.empty()) return InvalidArgument(field + " is empty; e.g. \"cv,ct\"");
  std::vector<MotionModelKind> modes;
  for (const std::string& entry : names) {
    auto kind = ParseMotionModelKind(entry, field + " entry");
    if (!kind.ok()) return kind.status();
    if (std::find(modes.begin(), modes.end(), *kind) != modes.end()) {
      return InvalidArgument(field + " '" + list + "' names '" + entry + "' twice");
    }
    modes.push_back(*kind);
  }
  return modes;
}

std::string ImmModesName(const std::vector<MotionModelKind>& modes) {
  std::string list;
  for (size_t i = 0; i < modes.size(); ++i) list += std::string(i == 0 ? "" : ",") + MotionModelKindName(modes[i]);
  return list;
}

Status ImmOptions::Validate() const {
  if (modes.empty() || modes.size() > 8) {
    return InvalidArgument("imm modes: 1 to 8 are needed, got " + std::to_string(modes.size()));
  }
  std::set<std::string> names;
  for (const ImmMode& m : modes) {
    const std::string name = m.name.empty() ? MotionModelKindName(m.motion_model) : m.name;
    if (!names.insert(name).second) return InvalidArgument("imm modes: the name '" + name + "' appears twice");
    KalmanOptions o = kalman;
    o.motion_model = m.motion_model;
    o.motion = m.motion;
    LOCALIZER_RETURN_IF_ERROR(o.Validate());
  }
  return ValidateStayProbability(stay_probability, "stay_probability");
}

struct ImmFilter::Impl {
  ArrayGeometry array;
  ImmOptions options;
  std::vector<std::unique_ptr<KalmanFilter>> modes;
  std::vector<std::string> names;
  MatrixXd switching;
  VectorXd mu;
  std::vector<double> log_likelihood;
  bool initialised = false;

  int count() const { return static_cast<int>(modes.size()); }
  // The mixing step: every mode restarts from its mixed prior. mu becomes cbar.
  Status Mix();
};

Status ImmFilter::Impl::Mix() {
  const VectorXd cbar = PredictModelProbabilities(switching, mu);
  std::vector<Embedded> mixed(count());
  for (int j = 0; j < count(); ++j) {
    const KalmanFilter& to = *modes[j];
    VectorXd x0 = VectorXd::Zero(to.state_dim());
    std::vector<Embedded> from(count());
    std::vector<double> weight(count(), 0.0);  // mu_{i|j}
    for (int i = 0; i < count(); ++i) {
      weight[i] = cbar(j) > 0.0 ? switching(i, j) * mu(i) / cbar(j) : (i == j ? 1.0 : 0.0);
      from[i] = Embed(*modes[i], to);
      x0 += weight[i] * from[i].x;
    }
    MatrixXd p0 = MatrixXd::Zero(to.state_dim(), to.state_dim());
    for (int i = 0; i < count(); ++i) {
      const VectorXd d = from[i].x - x0;
      p0 += weight[i] * (from[i].p + d * d.transpose());
    }
    mixed[j] = {std::move(x0), std::move(p0)};
  }
  // Only now overwrite the modes: every mixture above read the unmixed estimates.
  for (int j = 0; j < count(); ++j) LOCALIZER_RETURN_IF_ERROR(modes[j]->SetState(mixed[j].x, mixed[j].p));
  mu = cbar;
  return Status::Ok();
}

ImmFilter::ImmFilter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ImmFilter::~ImmFilter() = default;

StatusOr<std::unique_ptr<ImmFilter>> ImmFilter::Create(const ArrayGeometry& array, const ImmOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  auto impl = std::make_unique<Impl>(Impl{array, options, {}, {}, {}, {}, {}, false});
  for (const ImmMode& m : options.modes) {
    KalmanOptions o = options.kalman;
    o.motion_model = m.motion_model;
    o.motion = m.motion;
    auto filter = KalmanFilter::Create(array, o);
    if (!filter.ok()) return filter.status();
    impl->modes.push_back(std::move(filter).value());
    impl->names.push_back(m.name.empty() ? MotionModelKindName(m.motion_model) : m.name);
  }
  const int k = impl->count();
  impl->switching = SwitchingMatrix(k, options.stay_probability);
  impl->mu = VectorXd::Constant(k, 1.0 / k);
  impl->log_likelihood.assign(k, 0.0);
  return std::unique_ptr<ImmFilter>(new ImmFilter(std::move(impl)));
}

bool ImmFilter::initialised() const { return impl_->initialised; }
const KalmanFilter& ImmFilter::mode(int j) const { return *impl_->modes.at(j); }

Status ImmFilter::Initialise(const TrackState& belief) {
  for (auto& m : impl_->modes) LOCALIZER_RETURN_IF_ERROR(m->Initialise(belief));
  impl_->mu.setConstant(1.0 / impl_->count());
  impl_->initialised = true;
  return Status::Ok();
}

void ImmFilter::Predict(double dt_s) {
  Impl& s = *impl_;
  if (!s.initialised || !(dt_s > 0.0)) return;
  // Mixed covariances are sums of PSD terms; SetState refuses only non-finite input, and
  // then the modes keep their unmixed estimates (and mu its value) rather than crash.
  const VectorXd before = s.mu;
  if (!s.Mix().ok()) s.mu = before;
  for (auto& m : s.modes) m->Predict(dt_s);
}

StatusOr<UpdateReport> ImmFilter::Update(const Measurement& m) {
  Impl& s = *impl_;
  if (!s.initialised) return FailedPrecondition("IMM filter updated before initialisation");
  std::vector<UpdateReport> reports(s.count());
  bool all_gated = true;
  for (int j = 0; j < s.count(); ++j) {
    auto report = s.modes[j]->Update(m);
    if (!report.ok()) return report.status();
    reports[j] = *report;
    all_gated &= report->gated;
    s.log_likelihood[j] = s.modes[j]->last_log_likelihood();
  }
  if (reports[0].pair_count > 0 && !all_gated) (void)UpdateModelProbabilities(s.log_likelihood, &s.mu);
  Eigen::Index best = 0;
  s.mu.maxCoeff(&best);
  UpdateReport report = reports[best];
  report.gated = reports[0].pair_count > 0 && all_gated;
  report.ess = 0.0;
  return report;
}

TrackState ImmFilter::State() const {
  const Impl& s = *impl_;
  TrackState state;
  if (!s.initialised) return state;
  for (int j = 0; j < s.count(); ++j) state.mean += s.mu(j) * s.modes[j]->mean().head<6>();
  for (int j = 0; j < s.count(); ++j) {
    const Vec6 d = s.modes[j]->mean().head<6>() - state.mean;
    state.covariance += s.mu(j) * (s.modes[j]->covariance().topLeftCorner<6, 6>() + d * d.transpose());
  }
  return state;
}

std::vector<ModelProbability> ImmFilter::ModelProbabilities() const {
  std::vector<ModelProbability> out;
  if (!impl_->initialised) return out;
  for (int j = 0; j < impl_->count(); ++j) out.push_back({impl_->names[j], impl_->mu(j)});
  return out;
}

}  // namespace localizer::engine

namespace localizer::engine {

Status ImmFilter::SetArray(const ArrayGeometry& array) {
  LOCALIZER_RETURN_IF_ERROR(ValidateMovedArray(impl_->array, array));
  impl_->array = array;
  for (auto& mode : impl_->modes) LOCALIZER_RETURN_IF_ERROR(mode->SetArray(array));
  return Status::Ok();
}

}  // namespace localizer::engine
