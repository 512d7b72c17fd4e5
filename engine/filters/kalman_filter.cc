#include "engine/filters/kalman_filter.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>
#include <vector>

#include "engine/core/enum_names.h"
#include "engine/filters/divergence_monitor.h"

namespace localizer::engine {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// Symmetrise, and lift eigenvalues that rounding pushed below 1e-12 of the largest.
void Repair(MatrixXd* p) {
  *p = 0.5 * (*p + p->transpose());
  const Eigen::LLT<MatrixXd> llt(*p);
  if (llt.info() == Eigen::Success) return;
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(*p);
  const double floor = 1e-12 * std::max(1e-30, eig.eigenvalues().maxCoeff());
  *p = eig.eigenvectors() * eig.eigenvalues().cwiseMax(floor).asDiagonal() * eig.eigenvectors().transpose();
}

// The used pairs: their numbers, measured delays (z) and noise variances (r).
struct UsedPairs {
  std::vector<int> index;  // pair numbers
  VectorXd z, r;
};

// The prior's view of a frame: predicted TDOAs, S = H P H^T + R, P H^T, and (EKF) H.
struct Innovation {
  VectorXd predicted;
  MatrixXd s_cov, cross, h;
};

constexpr EnumName<KalmanVariant> kKalmanVariants[] = {{KalmanVariant::kExtended, "ekf"},
                                                       {KalmanVariant::kUnscented, "ukf"}};
constexpr EnumName<RobustUpdate> kRobustUpdates[] = {
    {RobustUpdate::kNone, "none"}, {RobustUpdate::kHuber, "huber"}, {RobustUpdate::kStudentT, "student-t"}};

}  // namespace

StatusOr<KalmanVariant> ParseKalmanVariant(const std::string& name, const std::string& field) {
  return ParseEnumName(name, field, kKalmanVariants);
}

const char* KalmanVariantName(KalmanVariant variant) { return EnumNameOf(variant, kKalmanVariants); }

StatusOr<RobustUpdate> ParseRobustUpdate(const std::string& name, const std::string& field) {
  return ParseEnumName(name, field, kRobustUpdates);
}

const char* RobustUpdateName(RobustUpdate robust) { return EnumNameOf(robust, kRobustUpdates); }

Status KalmanOptions::Validate() const {
  if (!(tdoa_sigma_s >= 0.0) || !std::isfinite(tdoa_sigma_s)) {
    return InvalidArgument("tdoa_sigma_s must be finite and >= 0 (0: adaptive)");
  }
  if (!(min_peak_snr >= 0.0) || !std::isfinite(min_peak_snr))
    return InvalidArgument("min_peak_snr must be finite and >= 0");
  if (!(gate_probability > 0.0 && gate_probability <= 1.0))
    return InvalidArgument("gate_probability must be in (0, 1]");
  if (!(extra_state_std >= 0.0) || !std::isfinite(extra_state_std)) {
    return InvalidArgument("extra_state_std must be finite and >= 0");
  }
  if (!(huber_threshold > 0.0) || !std::isfinite(huber_threshold)) {
    return InvalidArgument("huber_threshold must be finite and > 0");
  }
  if (!(student_dof > 0.0) || !std::isfinite(student_dof)) return InvalidArgument("student_dof must be finite and > 0");
  return MakeMotionModel(motion_model, motion).status();
}

struct KalmanFilter::Impl {
  Impl(const ArrayGeometry& a, const KalmanOptions& o, std::unique_ptr<MotionModel> m)
      : array(a), options(o), model(std::move(m)), noise(o.tdoa_sigma_s) {}

  // h(x) for the used pairs, with the half-delay timing correction (see the header).
  VectorXd Measure(const VectorXd& state, const UsedPairs& used) const {
    const Vec3 pos = state.head<3>(), vel = state.segment<3>(3);
    const VectorXd t = array.Tdoa(pos);
    const MatrixXd j = array.TdoaJacobian(pos);
    VectorXd h(used.index.size());
    for (size_t i = 0; i < used.index.size(); ++i) {
      const int k = used.index[i];
      h(i) = t(k) - 0.5 * used.z(i) * j.row(k).dot(vel);
    }
    return h;
  }
  MatrixXd MeasureJacobian(const VectorXd& state, const UsedPairs& used) const {
    const MatrixXd j = array.TdoaJacobian(state.head<3>());
    MatrixXd h = MatrixXd::Zero(used.index.size(), state.size());
    for (size_t i = 0; i < used.index.size(); ++i) {
      const int k = used.index[i];
      h.block(i, 0, 1, 3) = j.row(k);
      h.block(i, 3, 1, 3) = -0.5 * used.z(i) * j.row(k);
    }
    return h;
  }
  // Scaled sigma points (alpha 1, beta 2, kappa 0) of (mean, cov): columns.
  MatrixXd SigmaPoints(const VectorXd& m, const MatrixXd& c, VectorXd* wm, VectorXd* wc) const {
    const int n = static_cast<int>(m.size());
    const double lambda = 0.0;  // alpha^2 (n + kappa) - n with alpha 1, kappa 0
    Eigen::LLT<MatrixXd> llt((n + lambda) * c);
    MatrixXd root;
    if (llt.info() == Eigen::Success) {
      root = llt.matrixL();
    } else {  // semi-definite: the eigen square root
      const Eigen::SelfAdjointEigenSolver<MatrixXd> eig((n + lambda) * c);
      root = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
    }
    MatrixXd points(n, 2 * n + 1);
    points.col(0) = m;
    for (int i = 0; i < n; ++i) {
      points.col(1 + i) = m + root.col(i);
      points.col(1 + n + i) = m - root.col(i);
    }
    wm->setConstant(2 * n + 1, 1.0 / (2.0 * (n + lambda)));
    *wc = *wm;
    (*wm)(0) = lambda / (n + lambda);
    (*wc)(0) = (*wm)(0) + 2.0;  // + (1 - alpha^2 + beta)
    return points;
  }

  UsedPairs Collect(const Measurement& m, int count) const {
    UsedPairs used;
    used.z.resize(count);
    used.r.resize(count);
    for (int k = 0, i = 0; k < static_cast<int>(m.pairs.size()); ++k) {
      if (!noise.used()[k]) continue;
      used.index.push_back(k);
      used.z(i) = m.pairs[k].delay_s;
      used.r(i) = noise.sigmas_s()[k] * noise.sigmas_s()[k];
      ++i;
    }
    return used;
  }
  // The predicted TDOAs under the prior, S = H P H^T + R and P H^T (EKF: linearised at the
  // mean; UKF: over the sigma points).
  Innovation Innovate(const UsedPairs& used, const MatrixXd& r) const {
    Innovation in;
    const int count = static_cast<int>(used.index.size());
    if (options.variant == KalmanVariant::kExtended) {
      in.predicted = Measure(x, used);
      in.h = MeasureJacobian(x, used);
      in.cross = p * in.h.transpose();
      in.s_cov = in.h * in.cross + r;
      return in;
    }
    VectorXd wm, wc;
    const MatrixXd points = SigmaPoints(x, p, &wm, &wc);
    MatrixXd zs(count, points.cols());
    for (int i = 0; i < points.cols(); ++i) zs.col(i) = Measure(points.col(i), used);
    in.predicted = zs * wm;
    in.s_cov = r;
    in.cross = MatrixXd::Zero(x.size(), count);
    for (int i = 0; i < points.cols(); ++i) {
      const VectorXd dz = zs.col(i) - in.predicted;
      in.s_cov += wc(i) * dz * dz.transpose();
      in.cross += wc(i) * (points.col(i) - x) * dz.transpose();
    }
    return in;
  }
  // Robust reweighting by iterated least squares (see the header): the noise variances
  // R_k / w_k, w_k from the residual e_k at the reweighted update.
  double Weight(double e) const {
    if (options.robust == RobustUpdate::kHuber) return e > options.huber_threshold ? options.huber_threshold / e : 1.0;
    return std::min(1.0, (options.student_dof + 1.0) / (options.student_dof + e * e));
  }
  VectorXd RobustVariances(const UsedPairs& used, const VectorXd& nu, const Innovation& in) const {
    constexpr int kMaxPasses = 10;
    constexpr double kTolerance = 1e-3, kMinWeight = 1e-8;
    const VectorXd sigma = used.r.cwiseSqrt();
    MatrixXd hph = in.s_cov;
    hph.diagonal() -= used.r;
    VectorXd w = VectorXd::Ones(nu.size());
    for (int pass = 0; pass < kMaxPasses; ++pass) {
      MatrixXd s_w = hph;
      s_w.diagonal() += used.r.cwiseQuotient(w);
      const Eigen::LLT<MatrixXd> llt(s_w);
      if (llt.info() != Eigen::Success) break;
      const VectorXd updated = x + in.cross * llt.solve(nu);
      const VectorXd e = (used.z - Measure(updated, used)).cwiseQuotient(sigma).cwiseAbs();
      VectorXd next(w.size());
      for (Eigen::Index k = 0; k < w.size(); ++k) next(k) = std::max(kMinWeight, Weight(e(k)));
      const double moved = (next - w).cwiseAbs().maxCoeff();
      w = next;
      if (moved < kTolerance) break;
    }
    return used.r.cwiseQuotient(w);
  }

  void PredictEkf(double dt_s) {
    const MatrixXd f = model->Jacobian(x, dt_s);
    const MatrixXd q = model->ProcessNoise(x, dt_s);
    x = model->Propagate(x, dt_s);
    p = f * p * f.transpose() + q;
    Repair(&p);
  }
  void PredictUkf(double dt_s) {
    VectorXd wm, wc;
    const MatrixXd points = SigmaPoints(x, p, &wm, &wc);
    MatrixXd moved(points.rows(), points.cols());
    for (int i = 0; i < points.cols(); ++i) moved.col(i) = model->Propagate(points.col(i), dt_s);
    const VectorXd mean = moved * wm;
    MatrixXd cov = model->ProcessNoise(x, dt_s);
    for (int i = 0; i < moved.cols(); ++i) cov += wc(i) * (moved.col(i) - mean) * (moved.col(i) - mean).transpose();
    x = mean;
    p = cov;
    Repair(&p);
  }

  ArrayGeometry array;
  KalmanOptions options;
  std::unique_ptr<MotionModel> model;
  PairNoise noise;
  bool initialised = false;
  VectorXd x;
  MatrixXd p;
  double log_likelihood = 0.0;  // of the last update that used pairs
};

KalmanFilter::KalmanFilter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
KalmanFilter::~KalmanFilter() = default;

StatusOr<std::unique_ptr<KalmanFilter>> KalmanFilter::Create(const ArrayGeometry& array, const KalmanOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  auto model = MakeMotionModel(options.motion_model, options.motion);
  if (!model.ok()) return model.status();
  return std::unique_ptr<KalmanFilter>(
      new KalmanFilter(std::make_unique<Impl>(array, options, std::move(model).value())));
}

bool KalmanFilter::initialised() const { return impl_->initialised; }
const Eigen::VectorXd& KalmanFilter::mean() const { return impl_->x; }
const Eigen::MatrixXd& KalmanFilter::covariance() const { return impl_->p; }
int KalmanFilter::state_dim() const { return impl_->model->state_dim(); }
const char* KalmanFilter::motion_model_name() const { return impl_->model->name(); }
double KalmanFilter::last_log_likelihood() const { return impl_->log_likelihood; }

Status KalmanFilter::SetState(const Eigen::VectorXd& mean, const Eigen::MatrixXd& covariance) {
  const int n = state_dim();
  if (mean.size() != n || covariance.rows() != n || covariance.cols() != n) {
    return InvalidArgument("state must have " + std::to_string(n) + " entries and an " + std::to_string(n) + "x" +
                           std::to_string(n) + " covariance");
  }
  if (!mean.allFinite() || !covariance.allFinite()) return InvalidArgument("state mean or covariance is not finite");
  MatrixXd p = 0.5 * (covariance + covariance.transpose());
  if (Eigen::LLT<MatrixXd>(p).info() != Eigen::Success) {  // not definite: semi-definite at least?
    const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(p, Eigen::EigenvaluesOnly);
    if (eig.eigenvalues().minCoeff() < -1e-9 * std::max(1.0, eig.eigenvalues().maxCoeff())) {
      return InvalidArgument("state covariance is not positive semi-definite");
    }
  }
  Repair(&p);
  impl_->x = mean;
  impl_->p = std::move(p);
  impl_->initialised = true;
  return Status::Ok();
}

Status KalmanFilter::Initialise(const TrackState& belief) {
  LOCALIZER_RETURN_IF_ERROR(BeliefRoot(belief).status());  // finite and PSD
  Impl& s = *impl_;
  const int n = s.model->state_dim();
  s.x = VectorXd::Zero(n);
  s.x.head<6>() = belief.mean;
  s.p = MatrixXd::Zero(n, n);
  s.p.topLeftCorner<6, 6>() = 0.5 * (belief.covariance + belief.covariance.transpose());
  for (int i = 6; i < n; ++i) s.p(i, i) = s.options.extra_state_std * s.options.extra_state_std;
  Repair(&s.p);
  s.initialised = true;
  return Status::Ok();
}

void KalmanFilter::Predict(double dt_s) {
  if (!impl_->initialised || !(dt_s > 0.0)) return;
  if (impl_->options.variant == KalmanVariant::kExtended)
    impl_->PredictEkf(dt_s);
  else
    impl_->PredictUkf(dt_s);
}

StatusOr<UpdateReport> KalmanFilter::Update(const Measurement& m) {
  Impl& s = *impl_;
  if (!s.initialised) return FailedPrecondition("Kalman filter updated before initialisation");
  if (static_cast<int>(m.pairs.size()) != s.array.pair_count()) {
    return InvalidArgument("measurement has " + std::to_string(m.pairs.size()) + " pairs; the array has " +
                           std::to_string(s.array.pair_count()));
  }
  if (!(m.sample_rate_hz > 0.0)) return InvalidArgument("measurement sample_rate_hz must be > 0");
  UpdateReport report;
  const int count = s.noise.Select(m, s.options.min_peak_snr);
  if (count == 0) {
    report.tdoa_sigma_s = s.noise.rms_sigma_s();
    return report;
  }
  const UsedPairs used = s.Collect(m, count);
  const MatrixXd r = used.r.asDiagonal();
  const Innovation in = s.Innovate(used, r);
  const VectorXd nu = used.z - in.predicted;
  const Eigen::LLT<MatrixXd> s_llt(in.s_cov);
  if (s_llt.info() != Eigen::Success) return Internal("innovation covariance is not positive definite");
  const double nis = nu.dot(s_llt.solve(nu));
  // Innovation moments per pair for the NIS and the adaptive noise (prior spread of h).
  std::vector<InnovationMoments> innovations(m.pairs.size());
  for (int i = 0; i < count; ++i) {
    innovations[used.index[i]].mean_s = nu(i);
    innovations[used.index[i]].predicted_var_s2 = std::max(0.0, in.s_cov(i, i) - used.r(i));
  }
  s.noise.Finish(innovations, m.sample_rate_hz, &report);
  report.nis = nis;  // the joint NIS (Finish summed the per-pair ones)
  report.pair_count = count;
  // The noise, S and its factor the correction uses: as measured, or Huber-reweighted.
  MatrixXd r_used, s_used;
  Eigen::LLT<MatrixXd> w_llt;
  const bool robust = s.options.robust != RobustUpdate::kNone;
  if (robust) {
    r_used = s.RobustVariances(used, nu, in).asDiagonal();
    s_used = in.s_cov - r + r_used;
    w_llt.compute(s_used);
    if (w_llt.info() != Eigen::Success) return Internal("reweighted innovation covariance is not positive definite");
  }
  const Eigen::LLT<MatrixXd>& llt = robust ? w_llt : s_llt;
  const double gate_nis = robust ? nu.dot(w_llt.solve(nu)) : nis;
  const double log_det = 2.0 * llt.matrixLLT().diagonal().array().log().sum();
  s.log_likelihood = -0.5 * (gate_nis + log_det + count * std::log(2.0 * std::numbers::pi));
  if (s.options.gate_probability < 1.0 && gate_nis > ChiSquareQuantile(s.options.gate_probability, count)) {
    report.gated = true;  // an outlier frame leaves the state alone
    return report;
  }
  const MatrixXd gain = llt.solve(in.cross.transpose()).transpose();  // K = P H^T S^-1
  s.x += gain * nu;
  if (s.options.variant == KalmanVariant::kExtended) {
    const MatrixXd i_kh = MatrixXd::Identity(s.x.size(), s.x.size()) - gain * in.h;
    s.p = i_kh * s.p * i_kh.transpose() + gain * (robust ? r_used : r) * gain.transpose();  // Joseph form
  } else {
    s.p -= gain * (robust ? s_used : in.s_cov) * gain.transpose();
  }
  Repair(&s.p);
  return report;
}

TrackState KalmanFilter::State() const {
  TrackState state;
  if (!impl_->initialised) return state;
  state.mean = impl_->x.head<6>();
  state.covariance = impl_->p.topLeftCorner<6, 6>();
  return state;
}

}  // namespace localizer::engine

namespace localizer::engine {

Status KalmanFilter::SetArray(const ArrayGeometry& array) {
  LOCALIZER_RETURN_IF_ERROR(ValidateMovedArray(impl_->array, array));
  impl_->array = array;
  return Status::Ok();
}

}  // namespace localizer::engine
