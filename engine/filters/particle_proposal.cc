// Proposals that look at the measurement (particle_set.h): a share of a label's particles
// redrawn around the fix this frame gives near it, weighted so that the set still carries
// the label's predicted density.
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "engine/core/fast_math.h"
#include "engine/filters/particle_set.h"

namespace localizer::engine {
namespace {

// The share of a proposed label's particles that are redrawn around the fix: half keep
// the prior's spread (the fix may be the wrong one), half sit where the likelihood is.
constexpr double kFixProposalShare = 0.5;
// The proposal's spread over the fix's own (its CRLB): a little wider, so the Student-t
// likelihood's shoulders are sampled too (in 3-D, 1.5 x keeps ~58 % of the proposed
// particles' ESS against an exact match).
constexpr double kProposalSpread = 1.5;
// The fix must lie within this Mahalanobis distance of the label's prior (the prior and
// the fix's covariances summed): beyond, the label's predicted density does not reach it.
constexpr double kPriorGate = 5.0;
constexpr int kGaussNewtonIterations = 20;

struct LocalFix {
  Vec3 position_m;
  Mat3 covariance_m2;
};

// Gauss-Newton on the used pairs' delays from `start`, steps halved until the cost falls:
// the exact or least-squares solution in the basin the label sits in, and its CRLB over the
// used pairs. Not Multilaterate (multilateration.h): that starts from the closed form's
// candidates and keeps the best, where each label needs the solution nearest itself.
std::optional<LocalFix> FixFrom(const ArrayGeometry& array, const Measurement& m, const std::vector<int>& used,
                                int used_pairs, const std::vector<double>& sigmas_s, const Vec3& start) {
  const int pairs = array.pair_count();
  auto cost_and_normal = [&](const Vec3& x, Mat3* a, Vec3* g) {
    const Eigen::VectorXd h = array.Tdoa(x);
    const Eigen::MatrixXd j = array.TdoaJacobian(x);
    double cost = 0.0;
    if (a != nullptr) a->setZero();
    if (g != nullptr) g->setZero();
    for (int p = 0; p < pairs; ++p) {
      const size_t k = static_cast<size_t>(p);
      if (used[k] == 0 || !(sigmas_s[k] > 0.0)) continue;
      const double inv = 1.0 / sigmas_s[k];
      const double r = (m.pairs[k].delay_s - h(p)) * inv;
      cost += r * r;
      const Vec3 row = j.row(p).transpose() * inv;
      if (a != nullptr) *a += row * row.transpose();
      if (g != nullptr) *g += row * r;
    }
    return cost;
  };
  Vec3 x = start;
  Mat3 a;
  Vec3 g;
  double cost = cost_and_normal(x, &a, &g);
  for (int it = 0; it < kGaussNewtonIterations; ++it) {
    const Eigen::LDLT<Mat3> solve(a);
    if (solve.info() != Eigen::Success) return std::nullopt;
    Vec3 step = solve.solve(g);
    if (!step.allFinite()) return std::nullopt;
    double next = cost_and_normal(x + step, nullptr, nullptr);
    for (int halve = 0; halve < 10 && !(next <= cost); ++halve) {
      step *= 0.5;
      next = cost_and_normal(x + step, nullptr, nullptr);
    }
    if (!(next <= cost)) break;
    x += step;
    cost = cost_and_normal(x, &a, &g);
    if (step.norm() < 1e-7) break;
  }
  const Eigen::LDLT<Mat3> info(a);
  if (info.info() != Eigen::Success || !(info.vectorD().minCoeff() > 0.0)) return std::nullopt;
  // Every used pair explained (an exact or near-exact solution): a fix the pairs disagree
  // about is no better a proposal than the prior.
  if (!(cost <= 4.0 * used_pairs)) return std::nullopt;
  LocalFix fix{x, info.solve(Mat3::Identity())};
  if (!fix.position_m.allFinite() || !fix.covariance_m2.allFinite()) return std::nullopt;
  return fix;
}

// N(d; 0, cov) in logs, up to the constant every 3-D Gaussian shares.
class Gaussian3 {
 public:
  explicit Gaussian3(const Mat3& cov) : llt_(cov) {
    const Mat3 root = llt_.matrixL();
    ok_ = llt_.info() == Eigen::Success && root.allFinite();
    if (ok_) half_log_det_ = root.diagonal().array().log().sum();
  }
  bool ok() const { return ok_; }
  Mat3 root() const { return llt_.matrixL(); }
  double Log(const Vec3& d) const { return -0.5 * llt_.matrixL().solve(d).squaredNorm() - half_log_det_; }

 private:
  Eigen::LLT<Mat3> llt_;
  bool ok_ = false;
  double half_log_det_ = 0.0;
};

// The ESS share that particles from a Gaussian prior N(0, P) keep under a Gaussian
// likelihood exp(-(x - d)' F^-1 (x - d) / 2), in logs: E[w]^2 / E[w^2] with
//   E[w]   = |F|^1/2   |P + F|^-1/2   exp(-d' (P + F)^-1 d / 2),
//   E[w^2] = |F/2|^1/2 |P + F/2|^-1/2 exp(-d' (P + F/2)^-1 d / 2).
// With P >> F and d = 0 it is 2^1.5 sqrt(|F| / |P|).
double LogEssShare(const Vec3& d, const Mat3& prior, const Mat3& fix) {
  const Mat3 sum = prior + fix, half = prior + 0.5 * fix;
  const double log_mean =
      0.5 * std::log(fix.determinant()) - 0.5 * std::log(sum.determinant()) - 0.5 * d.dot(sum.ldlt().solve(d));
  const double log_square = 0.5 * std::log((0.5 * fix).determinant()) - 0.5 * std::log(half.determinant()) -
                            0.5 * d.dot(half.ldlt().solve(d));
  return 2.0 * log_mean - log_square;
}

// A square root of a symmetric positive semi-definite 3 x 3 matrix (eigen; a collapsed
// direction gets none).
Mat3 SymmetricRoot(const Mat3& cov) {
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(0.5 * (cov + cov.transpose()));
  return eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
}

}  // namespace

int ProposeLocalFixes(ParticleSet* set, const ArrayGeometry& array, const Measurement& m, const std::vector<int>& used,
                      const std::vector<double>& sigmas_s, double collapse_fraction) {
  int used_pairs = 0;
  for (int u : used) used_pairs += u != 0;
  if (used_pairs < 3 || !(collapse_fraction > 0.0)) return 0;
  std::vector<ParticleSet::FixProposal> proposals;
  for (const ParticleSet::LabelPrior& label : set->LabelPriors()) {
    const Vec3 mean = label.mean.head<3>();
    const Mat3 prior = label.covariance.topLeftCorner<3, 3>();
    const std::optional<LocalFix> fix = FixFrom(array, m, used, used_pairs, sigmas_s, mean);
    if (!fix) continue;
    const Vec3 d = fix->position_m - mean;
    const Mat3 spread = prior + fix->covariance_m2;
    const Eigen::LDLT<Mat3> gate(spread);
    if (gate.info() != Eigen::Success || !(d.dot(gate.solve(d)) < kPriorGate * kPriorGate)) continue;
    const double log_share = LogEssShare(d, prior, fix->covariance_m2);
    if (!(std::isfinite(log_share) && log_share < std::log(collapse_fraction))) continue;
    proposals.push_back({label.label, fix->position_m, kProposalSpread * kProposalSpread * fix->covariance_m2});
  }
  if (!proposals.empty()) set->ProposeAroundFixes(proposals, kFixProposalShare);
  return static_cast<int>(proposals.size());
}

void ParticleSet::ProposeAroundFixes(const std::vector<FixProposal>& proposals, double share) {
  if (proposals.empty() || !(share > 0.0 && share < 1.0)) return;
  const std::vector<LabelPrior> priors = LabelPriors();
  const std::array<float*, 6> cols = cur_.Pointers();
  const uint32_t key = NextKey();
  moments_valid_ = false;
  for (const FixProposal& proposal : proposals) {
    const auto prior =
        std::find_if(priors.begin(), priors.end(), [&](const LabelPrior& p) { return p.label == proposal.label; });
    if (prior == priors.end()) continue;
    // The label's Gaussian prior, relative to the set's origin: position p(x), and the
    // velocity given the position, v | x ~ N(mv + Kvx (x - mx), Pvv - Kvx Pxv).
    const Vec3 mx = prior->mean.head<3>() - origin_m_;
    const Vec3 mv = prior->mean.tail<3>();
    const Mat3 pxx = prior->covariance.topLeftCorner<3, 3>();
    const Mat3 pvx = prior->covariance.bottomLeftCorner<3, 3>();
    const Eigen::LDLT<Mat3> pxx_solve(pxx);
    if (pxx_solve.info() != Eigen::Success) continue;
    const Mat3 gain = pxx_solve.solve(pvx.transpose()).transpose();  // Kvx = Pvx Pxx^-1
    const Mat3 cond = prior->covariance.bottomRightCorner<3, 3>() - gain * pvx.transpose();
    const Mat3 cond_root = SymmetricRoot(cond);
    const Vec3 fix = proposal.position_m - origin_m_;
    const Gaussian3 p_density(pxx), q_density(proposal.covariance_m2);
    if (!p_density.ok() || !q_density.ok()) continue;
    const Mat3 q_root = q_density.root();
    const int label = proposal.label;
    const bool single = labels_ <= 1;
    // Which of the label's particles are redrawn: the first, then every one whose running
    // count crosses a multiple of 1 / share (the first: MeanAndCovariance sums about particle
    // 0, which should sit where the weight will be). Counted first, so the density below
    // uses the share drawn.
    const auto redrawn = [share](int member) { return std::ceil((member + 1) * share) > std::ceil(member * share); };
    int members = 0, drawn = 0;
    for (int i = 0; i < n_; ++i) {
      if (!single && label_[static_cast<size_t>(i)] != label) continue;
      drawn += redrawn(members++);
    }
    if (drawn == 0 || drawn == members) continue;
    const double s = static_cast<double>(drawn) / members;
    members = 0;
    for (int i = 0; i < n_; ++i) {
      if (!single && label_[static_cast<size_t>(i)] != label) continue;
      const bool redraw = redrawn(members++);
      const uint32_t counter = 6u * static_cast<uint32_t>(i);
      if (redraw) {
        Vec3 z, u;
        for (int k = 0; k < 3; ++k) {
          z(k) = NormalFromUniform(UniformFromCounter(key, counter + static_cast<uint32_t>(k)));
          u(k) = NormalFromUniform(UniformFromCounter(key, counter + 3u + static_cast<uint32_t>(k)));
        }
        const Vec3 x = fix + q_root * z;
        const Vec3 v = mv + gain * (x - mx) + cond_root * u;
        for (int k = 0; k < 3; ++k) {
          cols[static_cast<size_t>(k)][i] = static_cast<float>(x(k));
          cols[static_cast<size_t>(k) + 3][i] = static_cast<float>(v(k));
        }
      }
      const Vec3 x(cols[0][i], cols[1][i], cols[2][i]);
      const double log_p = p_density.Log(x - mx);
      const double log_q = q_density.Log(x - fix);
      // log p - log((1 - s) p + s q), computed stably.
      const double ratio = log_q - log_p + std::log(s / (1.0 - s));
      const double log_mix =
          std::log(1.0 - s) + (ratio > 0.0 ? ratio + std::log1p(std::exp(-ratio)) : std::log1p(std::exp(ratio)));
      logw_[static_cast<size_t>(i)] -= static_cast<float>(log_mix);
    }
  }
  if (bounded_) ApplyBounds();
  NormaliseWeights();
}

}  // namespace localizer::engine
