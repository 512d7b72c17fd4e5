#include "engine/filters/kalman_filter.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <vector>

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

}  // namespace

Status KalmanOptions::Validate() const {
  if (!(tdoa_sigma_s >= 0.0) || !std::isfinite(tdoa_sigma_s)) {
    return InvalidArgument("tdoa_sigma_s must be finite and >= 0 (0: adaptive)");
  }
  if (!(min_peak_snr >= 0.0) || !std::isfinite(min_peak_snr)) return InvalidArgument("min_peak_snr must be finite and >= 0");
  if (!(gate_probability > 0.0 && gate_probability <= 1.0)) return InvalidArgument("gate_probability must be in (0, 1]");
  if (!(extra_state_std >= 0.0) || !std::isfinite(extra_state_std)) {
    return InvalidArgument("extra_state_std must be finite and >= 0");
  }
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
};

KalmanFilter::KalmanFilter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
KalmanFilter::~KalmanFilter() = default;

StatusOr<std::unique_ptr<KalmanFilter>> KalmanFilter::Create(const ArrayGeometry& array, const KalmanOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  auto model = MakeMotionModel(options.motion_model, options.motion);
  if (!model.ok()) return model.status();
  return std::unique_ptr<KalmanFilter>(new KalmanFilter(std::make_unique<Impl>(array, options, std::move(model).value())));
}

bool KalmanFilter::initialised() const { return impl_->initialised; }
const Eigen::VectorXd& KalmanFilter::mean() const { return impl_->x; }
const Eigen::MatrixXd& KalmanFilter::covariance() const { return impl_->p; }
int KalmanFilter::state_dim() const { return impl_->model->state_dim(); }

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
  if (impl_->options.variant == KalmanVariant::kExtended) impl_->PredictEkf(dt_s);
  else impl_->PredictUkf(dt_s);
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
  UsedPairs used;
  used.z.resize(count);
  used.r.resize(count);
  for (int k = 0, i = 0; k < static_cast<int>(m.pairs.size()); ++k) {
    if (!s.noise.used()[k]) continue;
    used.index.push_back(k);
    used.z(i) = m.pairs[k].delay_s;
    used.r(i) = s.noise.sigmas_s()[k] * s.noise.sigmas_s()[k];
    ++i;
  }
  const MatrixXd r = used.r.asDiagonal();
  VectorXd predicted;
  MatrixXd s_cov, cross, h;  // S, and P H^T (the UKF's cross covariance)
  if (s.options.variant == KalmanVariant::kExtended) {
    predicted = s.Measure(s.x, used);
    h = s.MeasureJacobian(s.x, used);
    cross = s.p * h.transpose();
    s_cov = h * cross + r;
  } else {
    VectorXd wm, wc;
    const MatrixXd points = s.SigmaPoints(s.x, s.p, &wm, &wc);
    MatrixXd zs(count, points.cols());
    for (int i = 0; i < points.cols(); ++i) zs.col(i) = s.Measure(points.col(i), used);
    predicted = zs * wm;
    s_cov = r;
    cross = MatrixXd::Zero(s.x.size(), count);
    for (int i = 0; i < points.cols(); ++i) {
      const VectorXd dz = zs.col(i) - predicted;
      s_cov += wc(i) * dz * dz.transpose();
      cross += wc(i) * (points.col(i) - s.x) * dz.transpose();
    }
  }
  const VectorXd nu = used.z - predicted;
  const Eigen::LLT<MatrixXd> s_llt(s_cov);
  if (s_llt.info() != Eigen::Success) return Internal("innovation covariance is not positive definite");
  const double nis = nu.dot(s_llt.solve(nu));
  // Innovation moments per pair for the NIS and the adaptive noise (prior spread of h).
  std::vector<InnovationMoments> innovations(m.pairs.size());
  for (int i = 0; i < count; ++i) {
    innovations[used.index[i]].mean_s = nu(i);
    innovations[used.index[i]].predicted_var_s2 = std::max(0.0, s_cov(i, i) - used.r(i));
  }
  s.noise.Finish(innovations, m.sample_rate_hz, &report);
  report.nis = nis;  // the joint NIS (Finish summed the per-pair ones)
  report.pair_count = count;
  if (s.options.gate_probability < 1.0 && nis > ChiSquareQuantile(s.options.gate_probability, count)) {
    report.gated = true;  // an outlier frame leaves the state alone
    return report;
  }
  const MatrixXd gain = s_llt.solve(cross.transpose()).transpose();  // K = P H^T S^-1
  s.x += gain * nu;
  if (s.options.variant == KalmanVariant::kExtended) {
    const MatrixXd i_kh = MatrixXd::Identity(s.x.size(), s.x.size()) - gain * h;
    s.p = i_kh * s.p * i_kh.transpose() + gain * r * gain.transpose();  // Joseph form
  } else {
    s.p -= gain * s_cov * gain.transpose();
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
