// ParticleSet's several hypotheses (particle_set.h): mixture sampling, per-label moments,
// resampling that keeps each label's kernel its own, and position bounds.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include "engine/core/fast_math.h"
#include "engine/filters/particle_gather.h"
#include "engine/filters/particle_set.h"

namespace localizer::engine {
namespace {

constexpr int kMaxComponents = ParticleSet::kMaxLabels;

// Weight, mean and covariance per label, in the set's coordinates.
struct LabelMoments {
  std::array<double, kMaxComponents> weight{};
  std::array<Vec6, kMaxComponents> mean;
  std::array<Mat6, kMaxComponents> cov;
};

// a * b rounded to a double before it is added anywhere: Eigen's outer product, which the sums
// below reproduce, adds the rounded products (no fused multiply-add), so the covariances keep
// their last bits.
inline double RoundedProduct(double a, double b) {
  double p = a * b;
#if defined(__x86_64__) || defined(__i386__)
  asm("" : "+x"(p));  // an opaque value: the compiler cannot fuse it into the add
#else
  volatile double opaque = p;
  p = opaque;
#endif
  return p;
}

LabelMoments MomentsByLabel(int n, const std::array<const float*, 6>& cols, const std::vector<uint8_t>& label,
                            const float* w) {
  // One label at a time over its own particles (a counting sort keeps each label's in index
  // order), so that its sums stay in registers: indexed by each particle's label they went
  // through memory, ~60 % of a 16384-particle session's frame while several labels live.
  // Each sum adds the same products in the same order as one pass over all particles would.
  LabelMoments out;
  std::array<int, kMaxComponents + 1> first{};
  for (int i = 0; i < n; ++i) ++first[label[static_cast<size_t>(i)] + 1u];
  for (size_t c = 0; c < kMaxComponents; ++c) first[c + 1] += first[c];
  std::vector<int> order(static_cast<size_t>(n));
  {
    std::array<int, kMaxComponents> next{};
    for (size_t c = 0; c < kMaxComponents; ++c) next[c] = first[c];
    for (int i = 0; i < n; ++i) order[static_cast<size_t>(next[label[static_cast<size_t>(i)]]++)] = i;
  }
  const float* x0 = cols[0];
  const float* x1 = cols[1];
  const float* x2 = cols[2];
  const float* x3 = cols[3];
  const float* x4 = cols[4];
  const float* x5 = cols[5];
  for (size_t c = 0; c < kMaxComponents; ++c) {
    out.cov[c].setZero();
    out.mean[c].setZero();
    const int begin = first[c], end = first[c + 1];
    double weight = 0.0;
    double sum[6] = {};
    for (int t = begin; t < end; ++t) {
      const int i = order[static_cast<size_t>(t)];
      const double wi = w[i];
      weight += wi;
      sum[0] += wi * x0[i];
      sum[1] += wi * x1[i];
      sum[2] += wi * x2[i];
      sum[3] += wi * x3[i];
      sum[4] += wi * x4[i];
      sum[5] += wi * x5[i];
    }
    out.weight[c] = weight;
    if (!(weight > 0.0)) continue;
    const Vec6 mean = Vec6(sum[0], sum[1], sum[2], sum[3], sum[4], sum[5]) / weight;
    out.mean[c] = mean;
    double cov[6][6] = {};  // [column][row]: column k adds d_k (w d)
#if defined(__AVX512F__)
    // The same products and additions, one column of six rows per vector.
    {
      const __m512d centre = _mm512_maskz_loadu_pd(0x3f, mean.data());
      __m512d column[6];
      for (__m512d& v : column) v = _mm512_setzero_pd();
      for (int t = begin; t < end; ++t) {
        const int i = order[static_cast<size_t>(t)];
        const double d[6] = {x0[i] - mean(0), x1[i] - mean(1), x2[i] - mean(2),
                             x3[i] - mean(3), x4[i] - mean(4), x5[i] - mean(5)};
        const __m512d x = _mm512_setr_pd(x0[i], x1[i], x2[i], x3[i], x4[i], x5[i], 0.0, 0.0);
        const __m512d wd = _mm512_mul_pd(_mm512_set1_pd(w[i]), _mm512_sub_pd(x, centre));
        for (int k = 0; k < 6; ++k) {
          __m512d product = _mm512_mul_pd(_mm512_set1_pd(d[k]), wd);
          asm("" : "+v"(product));  // rounded before the add, as RoundedProduct
          column[k] = _mm512_add_pd(column[k], product);
        }
      }
      for (int k = 0; k < 6; ++k) _mm512_mask_storeu_pd(cov[k], 0x3f, column[k]);
    }
#else
    for (int t = begin; t < end; ++t) {
      const int i = order[static_cast<size_t>(t)];
      const double d[6] = {x0[i] - mean(0), x1[i] - mean(1), x2[i] - mean(2),
                           x3[i] - mean(3), x4[i] - mean(4), x5[i] - mean(5)};
      const double wi = w[i];
      double wd[6];
      for (int r = 0; r < 6; ++r) wd[r] = wi * d[r];
      for (int k = 0; k < 6; ++k) {
        for (int r = 0; r < 6; ++r) cov[k][r] += RoundedProduct(d[k], wd[r]);
      }
    }
#endif
    for (int k = 0; k < 6; ++k) {
      for (int r = 0; r < 6; ++r) out.cov[c](r, k) = cov[k][r] / weight;
    }
  }
  return out;
}

}  // namespace

void ParticleSet::SampleMixture(const std::vector<Component>& components) {
  const int k = std::min(static_cast<int>(components.size()), kMaxComponents);
  double total = 0.0;
  for (int c = 0; c < k; ++c) total += std::max(components[static_cast<size_t>(c)].weight, 0.0);
  // Counts: one each, the floor of each share of the rest, then the remainder in turn.
  std::vector<int> count(static_cast<size_t>(k), 1);
  int assigned = k;
  for (int c = 0; c < k; ++c) {
    const double share = total > 0.0 ? components[static_cast<size_t>(c)].weight / total : 1.0 / k;
    const int extra = std::max(0, static_cast<int>(std::floor(share * (n_ - k))));
    count[static_cast<size_t>(c)] += extra;
    assigned += extra;
  }
  for (int c = 0; assigned < n_; c = (c + 1) % k, ++assigned) ++count[static_cast<size_t>(c)];
  label_.assign(static_cast<size_t>(n_), 0);
  next_label_.assign(static_cast<size_t>(n_), 0);
  const uint32_t key = NextKey();
  int first = 0;
  for (int c = 0; c < k; ++c) {
    const Component& comp = components[static_cast<size_t>(c)];
    const int end = std::min(first + count[static_cast<size_t>(c)], n_);
    SampleGaussianRange(comp.mean, comp.root, key, first, end);
    std::fill(label_.begin() + first, label_.begin() + end, static_cast<uint8_t>(c));
    first = end;
  }
  labels_ = k;
  label_deficit_.fill(0.0f);
  DrawLevels();
  if (bounded_) ApplyBounds();
  SetEqualWeights();
}

void ParticleSet::ScoreLabels(float exponent) {
  std::array<float, kMaxComponents> best;
  best.fill(-INFINITY);
  const float* ll = loglik_.data();
  for (int i = 0; i < n_; ++i) {
    float& b = best[label_[static_cast<size_t>(i)]];
    b = std::max(b, ll[i]);
  }
  const float top = *std::max_element(best.begin(), best.end());
  for (int c = 0; c < labels_; ++c) {
    // One update adds at most kContenderStepNats: a single frame (an impulse, an echo on
    // two pairs) cannot end a contender that the frames before and after cannot tell apart.
    const float gap = std::isfinite(best[static_cast<size_t>(c)])
                          ? exponent * std::min(top - best[static_cast<size_t>(c)], kContenderStepNats)
                          : INFINITY;
    float& d = label_deficit_[static_cast<size_t>(c)];
    d = kContenderDecay * d + gap;
  }
}

std::vector<WeightedBelief> ParticleSet::Modes(double min_weight) const {
  if (labels_ <= 1) return {WeightedBelief{1.0, MeanAndCovariance()}};
  const LabelMoments m =
      MomentsByLabel(n_, {cur_.x.data(), cur_.y.data(), cur_.z.data(), cur_.vx.data(), cur_.vy.data(), cur_.vz.data()},
                     label_, w_.data());
  const std::array<double, kMaxComponents> weight = ContenderShares(m.weight);
  std::vector<WeightedBelief> out;
  double kept = 0.0;
  for (size_t c = 0; c < kMaxComponents; ++c) {
    if (!(weight[c] >= min_weight) || weight[c] <= 0.0) continue;
    WeightedBelief b;
    b.weight = weight[c];
    b.belief.mean = m.mean[c];
    b.belief.mean.head<3>() += origin_m_;
    b.belief.covariance = m.cov[c];
    kept += b.weight;
    out.push_back(b);
  }
  if (out.empty()) return {WeightedBelief{1.0, MeanAndCovariance()}};
  for (WeightedBelief& b : out) b.weight /= kept;
  std::sort(out.begin(), out.end(),
            [](const WeightedBelief& a, const WeightedBelief& b) { return a.weight > b.weight; });
  return out;
}

std::array<double, ParticleSet::kMaxLabels> ParticleSet::ContenderShares(const std::array<double, kMaxLabels>& weight,
                                                                         std::array<bool, kMaxLabels>* raised) const {
  // The heaviest few contenders below kContenderShare are raised to it; the other labels
  // share the rest in proportion to their weights.
  std::array<int, kMaxComponents> order;
  for (int c = 0; c < kMaxComponents; ++c) order[static_cast<size_t>(c)] = c;
  std::sort(order.begin(), order.end(),
            [&weight](int a, int b) { return weight[static_cast<size_t>(a)] > weight[static_cast<size_t>(b)]; });
  double total = 0.0;
  for (double w : weight) total += std::max(w, 0.0);
  std::array<double, kMaxComponents> share{};
  std::array<bool, kMaxComponents> held{};
  if (!(total > 0.0)) return share;
  double held_total = 0.0, free_total = 0.0;
  int contenders = 0;
  for (int c : order) {
    const size_t k = static_cast<size_t>(c);
    if (!(weight[k] > 0.0) || !Contender(c) || contenders >= kMaxContenders) continue;
    ++contenders;
    if (weight[k] / total < kContenderShare) {
      held[k] = true;
      held_total += kContenderShare;
    }
  }
  for (size_t c = 0; c < kMaxComponents; ++c) free_total += held[c] ? 0.0 : std::max(weight[c], 0.0);
  for (size_t c = 0; c < kMaxComponents; ++c) {
    if (held[c])
      share[c] = kContenderShare;
    else if (weight[c] > 0.0)
      share[c] = free_total > 0.0 ? weight[c] * (1.0 - held_total) / free_total : 0.0;
  }
  if (raised != nullptr) *raised = held;
  return share;
}

void ParticleSet::ResampleModes(double kernel_scale) {
  // Each label's moments before resampling: its kernel's shape and centre.
  std::array<Eigen::Matrix<float, 6, 6>, kMaxComponents> l;
  std::array<Eigen::Matrix<float, 6, 1>, kMaxComponents> shift;
  const double h = KernelBandwidth(kernel_scale, n_);
  const double a = kernel_scale > 0.0 ? KernelShrinkage(h) : 1.0;
  const std::array<const float*, 6> state{cur_.x.data(),  cur_.y.data(),  cur_.z.data(),
                                          cur_.vx.data(), cur_.vy.data(), cur_.vz.data()};
  LabelMoments moments = MomentsByLabel(n_, state, label_, w_.data());
  if (MergeCoincidentLabels(moments.weight, moments.mean, moments.cov)) {
    moments = MomentsByLabel(n_, state, label_, w_.data());
  }
  for (size_t c = 0; c < kMaxComponents; ++c) {
    l[c].setZero();
    shift[c].setZero();
    if (moments.weight[c] <= 0.0) continue;
    // Lower triangular: the move below reads z_0 .. z_r for row r.
    l[c] = (h * CovarianceRoot(moments.cov[c])).cast<float>();
    shift[c] = ((1.0 - a) * moments.mean[c]).cast<float>();
  }
  const std::array<double, kMaxComponents> carried = HoldContenders(moments.weight);
  SystematicIndices();
  CarryLevels();
  DrawKernelNoise();
  const std::array<float*, 6> from = cur_.Pointers(), to = next_.Pointers();
  const float fa = static_cast<float>(a);
  std::array<bool, kMaxComponents> alive{};
  int first = 0;
#if defined(__AVX512F__)
  // Whole blocks of 16 slots: parents read by GatherParents16, each slot's label's shift and
  // root picked by a permute from a vector that holds one label per lane, and the same fused
  // multiply-adds in the same order as the scalar loop below (GCC contracts its `v = fa * x +
  // s` and `v += l * z` into fused ones), so every value is the same bit for bit.
  static_assert(kMaxComponents == 16, "one lane per label");
  alignas(64) float shift_by_label[6][16];
  alignas(64) float root_by_label[21][16];  // row r's terms k = 0 .. r at r (r + 1) / 2 + k
  for (size_t c = 0; c < kMaxComponents; ++c) {
    for (int r = 0, t = 0; r < 6; ++r) {
      shift_by_label[r][c] = shift[c](r);
      for (int k = 0; k <= r; ++k) root_by_label[t++][c] = l[c](r, k);
    }
  }
  alignas(64) float parent[6][16];
  alignas(64) int slot_label[16];
  const __m512 va = _mm512_set1_ps(fa);
  for (; first + 16 <= n_; first += 16) {
    for (int k = 0; k < 16; ++k) {
      const int c = label_[static_cast<size_t>(index_[static_cast<size_t>(first + k)])];
      slot_label[k] = c;
      alive[static_cast<size_t>(c)] = true;
      next_label_[static_cast<size_t>(first + k)] = static_cast<uint8_t>(c);
    }
    const __m512i labels = _mm512_load_si512(slot_label);
    GatherParents16(from, index_.data() + first, n_, parent);
    for (int r = 0; r < 6; ++r) {
      __m512 v = _mm512_fmadd_ps(va, _mm512_load_ps(parent[r]),
                                 _mm512_permutexvar_ps(labels, _mm512_load_ps(shift_by_label[r])));
      if (kernel_scale > 0.0) {
        for (int k = 0; k <= r; ++k) {
          const __m512 root = _mm512_permutexvar_ps(labels, _mm512_load_ps(root_by_label[r * (r + 1) / 2 + k]));
          v = _mm512_fmadd_ps(root, _mm512_loadu_ps(noise_[static_cast<size_t>(k)].data() + first), v);
        }
      }
      _mm512_storeu_ps(to[static_cast<size_t>(r)] + first, v);
    }
  }
#endif
  for (int m = first; m < n_; ++m) {
    const int src = index_[static_cast<size_t>(m)];
    const int c = label_[static_cast<size_t>(src)];
    alive[static_cast<size_t>(c)] = true;
    next_label_[static_cast<size_t>(m)] = static_cast<uint8_t>(c);
    const Eigen::Matrix<float, 6, 6>& lc = l[static_cast<size_t>(c)];
    for (int r = 0; r < 6; ++r) {
      float v = fa * from[r][src] + shift[static_cast<size_t>(c)](r);
      if (kernel_scale > 0.0) {
        for (int k = 0; k <= r; ++k) v += lc(r, k) * noise_[static_cast<size_t>(k)][static_cast<size_t>(m)];
      }
      to[r][m] = v;
    }
  }
  std::swap(cur_, next_);
  std::swap(label_, next_label_);
  labels_ = static_cast<int>(std::count(alive.begin(), alive.end(), true));
  if (labels_ == 1) {
    std::fill(label_.begin(), label_.end(), 0);
    SetEqualWeights();
    return;
  }
  // Keep labels dense so the next pass stays within the live count.
  std::array<int, kMaxComponents> remap{};
  std::array<float, kMaxComponents> deficit{};
  std::array<double, kMaxComponents> weight{};
  int next = 0;
  for (size_t c = 0; c < kMaxComponents; ++c) {
    if (!alive[c]) continue;
    deficit[static_cast<size_t>(next)] = label_deficit_[c];
    weight[static_cast<size_t>(next)] = carried[c];
    remap[c] = next++;
  }
  for (uint8_t& lab : label_) lab = static_cast<uint8_t>(remap[lab]);
  label_deficit_ = deficit;
  SetLabelWeights(weight);
}

bool ParticleSet::MergeCoincidentLabels(const std::array<double, kMaxLabels>& weight,
                                        const std::array<Vec6, kMaxLabels>& mean,
                                        const std::array<Mat6, kMaxLabels>& covariance) {
  constexpr double kWithinSd2 = 6.0;  // Mahalanobis squared over 6 dimensions: one sd each
  // Each live label's covariance factored once.
  std::array<Eigen::LDLT<Mat6>, kMaxComponents> factor;
  for (size_t c = 0; c < kMaxComponents; ++c) {
    if (weight[c] > 0.0) factor[c].compute(covariance[c] + 1e-12 * Mat6::Identity());
  }
  const auto within = [&factor](size_t c, const Vec6& delta) {
    return factor[c].info() == Eigen::Success && delta.dot(factor[c].solve(delta)) < kWithinSd2;
  };
  std::array<int, kMaxComponents> into{};
  for (int c = 0; c < kMaxComponents; ++c) into[static_cast<size_t>(c)] = c;
  bool merged = false;
  // Lighter into heavier; a label already merged is not a target.
  for (size_t b = 0; b < kMaxComponents; ++b) {
    if (!(weight[b] > 0.0)) continue;
    for (size_t a = 0; a < kMaxComponents; ++a) {
      if (a == b || !(weight[a] > weight[b] || (weight[a] == weight[b] && a < b)) || into[a] != static_cast<int>(a)) {
        continue;
      }
      const Vec6 delta = mean[a] - mean[b];
      if (!within(a, delta) || !within(b, delta)) continue;
      into[b] = static_cast<int>(a);
      merged = true;
      break;
    }
  }
  if (!merged) return false;
  // A label merged into one that later merged on follows it.
  for (size_t c = 0; c < kMaxComponents; ++c) {
    while (into[static_cast<size_t>(into[c])] != into[c]) into[c] = into[static_cast<size_t>(into[c])];
  }
  for (uint8_t& lab : label_) lab = static_cast<uint8_t>(into[lab]);
  moments_valid_ = false;
  return true;
}

std::array<double, ParticleSet::kMaxLabels> ParticleSet::HoldContenders(const std::array<double, kMaxLabels>& weight) {
  std::array<bool, kMaxComponents> held{};
  const std::array<double, kMaxComponents> slots = ContenderShares(weight, &held);
  if (std::none_of(held.begin(), held.end(), [](bool h) { return h; })) return weight;
  // Scale each particle so its label's total is its share of the slots.
  std::array<float, kMaxComponents> scale{};
  for (size_t c = 0; c < kMaxComponents; ++c) {
    scale[c] = weight[c] > 0.0 ? static_cast<float>(slots[c] / weight[c]) : 0.0f;
  }
  for (int i = 0; i < n_; ++i) w_[static_cast<size_t>(i)] *= scale[label_[static_cast<size_t>(i)]];
  // What each label carries out of resampling: its marginal weight, bounded below while it is
  // held so that float underflow cannot end a hypothesis the data have not ruled out.
  std::array<double, kMaxComponents> carried = weight;
  for (size_t c = 0; c < kMaxComponents; ++c) {
    if (held[c]) carried[c] = std::max(weight[c], kMinHeldWeight);
  }
  return carried;
}

void ParticleSet::SetLabelWeights(const std::array<double, kMaxLabels>& weight) {
  // Each particle gets its label's weight over the label's count: the labels' totals are
  // the given weights (normalised), whatever share of the particles each holds.
  moments_valid_ = false;
  std::array<int, kMaxComponents> count{};
  for (int i = 0; i < n_; ++i) ++count[label_[static_cast<size_t>(i)]];
  double total = 0.0;
  for (size_t c = 0; c < kMaxComponents; ++c) total += count[c] > 0 ? weight[c] : 0.0;
  if (!(total > 0.0)) {
    SetEqualWeights();
    return;
  }
  std::array<float, kMaxComponents> per{};
  for (size_t c = 0; c < kMaxComponents; ++c) {
    per[c] = count[c] > 0 ? static_cast<float>(weight[c] / total / count[c]) : 0.0f;
  }
  for (int i = 0; i < n_; ++i) {
    const float wi = per[label_[static_cast<size_t>(i)]];
    w_[static_cast<size_t>(i)] = wi;
    logw_[static_cast<size_t>(i)] = std::log(wi);
  }
}

void ParticleSet::SetBounds(const Vec3& min_m, const Vec3& max_m) {
  bounded_ = false;
  for (int i = 0; i < 3; ++i) bounded_ |= std::isfinite(min_m(i)) || std::isfinite(max_m(i));
  // Infinite sides stay infinite in float; finite ones are shifted to the set's origin.
  bound_lo_ = (min_m - origin_m_).cast<float>();
  bound_hi_ = (max_m - origin_m_).cast<float>();
}

void ParticleSet::ApplyBounds() {
  // A particle that left the box is put back on its wall with the outward velocity removed
  // (a source cannot be outside): a cloud predicted out of the water as a whole would
  // otherwise keep going, every particle equally impossible and so equally weighted.
  moments_valid_ = false;
  const std::array<float*, 6> cols = cur_.Pointers();
  for (int axis = 0; axis < 3; ++axis) {
    float* __restrict p = cols[static_cast<size_t>(axis)];
    float* __restrict v = cols[static_cast<size_t>(axis) + 3];
    const float lo = bound_lo_(axis), hi = bound_hi_(axis);
    if (!std::isfinite(lo) && !std::isfinite(hi)) continue;
#pragma omp simd
    for (int i = 0; i < n_; ++i) {
      const bool below = p[i]<lo, above = p[i]> hi;
      v[i] = (below && v[i] < 0.0f) || (above && v[i] > 0.0f) ? 0.0f : v[i];
      p[i] = below ? lo : above ? hi : p[i];
    }
  }
}

std::vector<ParticleSet::LabelPrior> ParticleSet::LabelPriors() const {
  if (labels_ <= 1) {
    const TrackState all = MeanAndCovariance();
    return {LabelPrior{0, 1.0, all.mean, all.covariance}};
  }
  const LabelMoments m =
      MomentsByLabel(n_, {cur_.x.data(), cur_.y.data(), cur_.z.data(), cur_.vx.data(), cur_.vy.data(), cur_.vz.data()},
                     label_, w_.data());
  std::vector<LabelPrior> out;
  for (int c = 0; c < kMaxComponents; ++c) {
    const size_t k = static_cast<size_t>(c);
    if (!(m.weight[k] > 0.0)) continue;
    LabelPrior p{c, m.weight[k], m.mean[k], m.cov[k]};
    p.mean.head<3>() += origin_m_;
    out.push_back(p);
  }
  return out;
}

}  // namespace localizer::engine
