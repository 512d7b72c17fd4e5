#include "engine/tdoa/pair_fusion.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <vector>

#include "engine/tdoa/delay_statistics.h"
#include "engine/tdoa/peak_interpolation.h"

namespace localizer::engine {
namespace {

struct RefinedPeak {
  double lag = 0.0;        // samples
  double height = 0.0;     // normalised GCC at the peak (noise sds)
  double curvature = 0.0;  // of the normalised GCC at the peak, per sample^2 (< 0)
};

// A pair's kept GCC window, with the lags beyond it where the front end kept them.
struct Window {
  const std::vector<float>& gcc;
  const std::vector<float>* beyond;  // CrossPairGcc::gcc_beyond; null or empty: none
  int first_lag = 0;
  double inv_sigma = 0.0;  // normalisation to noise sds

  int size() const { return static_cast<int>(gcc.size()); }
  int reach() const { return beyond != nullptr ? static_cast<int>(beyond->size() / 2) : 0; }
  // Index i of the window; i < 0 and i >= size() read the lags beyond (within reach()).
  double At(int i) const {
    const int n = size();
    float v;
    if (i < 0) {
      v = (*beyond)[static_cast<size_t>(reach() + i)];
    } else if (i >= n) {
      v = (*beyond)[static_cast<size_t>(reach() + i - n)];
    } else {
      v = gcc[static_cast<size_t>(i)];
    }
    return v * inv_sigma;
  }
};

// The kPeakSamples samples of the window centred on index i; false when they run past what the
// window (and the lags beyond it) hold.
bool SamplesAround(const Window& w, int i, std::array<float, kPeakSamples>* s) {
  if (i - kPeakHalfWidth < -w.reach() || i + kPeakHalfWidth >= w.size() + w.reach()) return false;
  for (int m = 0; m < kPeakSamples; ++m)
    (*s)[static_cast<size_t>(m)] = static_cast<float>(w.At(i - kPeakHalfWidth + m));
  return true;
}

// The peak at lag first_lag + i + x: its height and curvature from the samples around i; false
// when it is not a maximum.
bool ShapeOf(const Window& w, int i, const std::array<float, kPeakSamples>& s, double x, RefinedPeak* out) {
  const std::span<const float, kPeakSamples> samples(s);
  out->lag = w.first_lag + i + x;
  out->height = SincReconstruct(samples, x);
  out->curvature = SincCurvature(samples, x);
  return out->curvature < 0.0 && out->height > 0.0;
}

// The peak at index i of the window, sinc-refined; false when it is not a maximum or lies
// within kPeakHalfWidth samples of what the window (and the lags beyond it) hold: a parabola
// there is biased by up to 0.06 sample, as much as the pairs' scatter at 10 dB, and such a
// bias moves the fused delays as one.
bool Refine(const Window& w, int i, RefinedPeak* out) {
  std::array<float, kPeakSamples> s;
  if (!SamplesAround(w, i, &s)) return false;
  return ShapeOf(w, i, s, InterpolatePeak(PeakInterpolation::kSinc, std::span<const float, kPeakSamples>(s)), out);
}

// A peak already refined (a reference pair's, at `lag` samples): its height and curvature
// there; false within kPeakHalfWidth samples of the window's end or when not a maximum.
bool ShapeAt(const Window& w, double lag, RefinedPeak* out) {
  const int i = static_cast<int>(std::lround(lag)) - w.first_lag;
  std::array<float, kPeakSamples> s;
  if (!SamplesAround(w, i, &s)) return false;
  return ShapeOf(w, i, s, lag - (w.first_lag + i), out);
}

// The largest local maximum of the window within lags [lo, hi] at or above min_value noise sds.
bool PeakNear(const Window& w, double lo, double hi, double min_value, RefinedPeak* out) {
  const int i0 = std::max(1, static_cast<int>(std::ceil(lo)) - w.first_lag);
  const int i1 = std::min(w.size() - 2, static_cast<int>(std::floor(hi)) - w.first_lag);
  int best = -1;
  for (int i = i0; i <= i1; ++i) {
    const double v = w.At(i);
    if (v < w.At(i - 1) || v < w.At(i + 1)) continue;
    if (best < 0 || v > w.At(best)) best = i;
  }
  if (best < 0 || w.At(best) < min_value) return false;
  return Refine(w, best, out);
}

// The quadratic-peak bound's shape, 1 / sqrt(height x -curvature) (gcc_phat.h: the delay's sd
// is 1 / (peak_snr sqrt(-g''/g)) where noise dominates the bins); its scale is calibrated.
double PeakShape(const RefinedPeak& p) { return 1.0 / std::sqrt(p.height * -p.curvature); }

// Reorders v.
double Median(std::vector<double>* v) {
  std::nth_element(v->begin(), v->begin() + static_cast<std::ptrdiff_t>(v->size() / 2), v->end());
  return (*v)[v->size() / 2];
}

}  // namespace

FusionReport PairFusion::Fuse(Measurement* m, std::span<const double> delay_rates) {
  FusionReport report;
  if (m == nullptr || m->cross_pairs.empty() || !(m->sample_rate_hz > 0.0)) return report;
  const double fs = m->sample_rate_hz;
  int max_sensor = 0;
  for (const PairMeasurement& p : m->pairs) max_sensor = std::max(max_sensor, p.sensor);
  node_of_sensor_.assign(static_cast<size_t>(max_sensor + 1), -1);
  pair_of_node_.clear();
  edges_.clear();

  // Reference edges; each usable pair's sigma x curvature calibrates the cross pairs' sigmas.
  std::vector<double>& calibration = calibration_;
  std::vector<double>& lag_of_node = lag_of_node_;
  std::vector<double>& sigma_of_node = sigma_of_node_;
  std::vector<double>& rate_of_node = rate_of_node_;
  calibration.clear();
  lag_of_node.clear();
  sigma_of_node.clear();
  rate_of_node.clear();
  for (size_t p = 0; p < m->pairs.size(); ++p) {
    const PairMeasurement& pm = m->pairs[p];
    const bool strong = pm.peak_snr >= kMinPeakSnr || pm.confirmed;
    if (!(pm.delay_sigma_s > 0.0) || !std::isfinite(pm.delay_s) || pm.gcc.empty() || !(pm.peak_value > 0.0) ||
        !strong) {
      continue;
    }
    const int node = static_cast<int>(pair_of_node_.size());
    node_of_sensor_[static_cast<size_t>(pm.sensor)] = node;
    pair_of_node_.push_back(static_cast<int>(p));
    const double lag = pm.delay_s * fs, sigma = pm.delay_sigma_s * fs;
    lag_of_node.push_back(lag);
    const double rate = p < delay_rates.size() ? delay_rates[p] : 0.0;
    rate_of_node.push_back(std::isfinite(rate) ? rate : 0.0);
    sigma_of_node.push_back(sigma);
    edges_.push_back({-1, node, lag, 1.0 / (sigma * sigma), true});
    RefinedPeak own;
    const Window window{pm.gcc, nullptr, pm.first_lag_samples, pm.peak_snr / pm.peak_value};
    if (ShapeAt(window, lag, &own)) calibration.push_back(sigma / PeakShape(own));
  }
  const int nodes = static_cast<int>(pair_of_node_.size());
  if (nodes < 2 || nodes > kMaxNodes) return report;
  // A cross pair's sigma is scale x PeakShape; the scale from the reference pairs whose peak
  // lies inside their window (none: a cross pair takes the rms of its two reference pairs').
  const double scale = calibration.empty() ? 0.0 : Median(&calibration);

  for (const CrossPairGcc& cp : m->cross_pairs) {
    if (cp.sensor_a > max_sensor || cp.sensor_b > max_sensor || !(cp.noise_floor_inverse > 0.0)) continue;
    const int a = node_of_sensor_[static_cast<size_t>(cp.sensor_a)];
    const int b = node_of_sensor_[static_cast<size_t>(cp.sensor_b)];
    if (a < 0 || b < 0) continue;
    const double predicted = lag_of_node[static_cast<size_t>(b)] - lag_of_node[static_cast<size_t>(a)];
    const double spread = std::hypot(sigma_of_node[static_cast<size_t>(a)], sigma_of_node[static_cast<size_t>(b)]);
    const double reach = std::clamp(3.0 * spread, 1.0, 3.0);
    RefinedPeak peak;
    const Window window{cp.gcc, &cp.gcc_beyond, cp.first_lag_samples, cp.noise_floor_inverse};
    if (!PeakNear(window, predicted - reach, predicted + reach, kMinCrossPeak, &peak)) continue;
    const double sigma = std::max(scale > 0.0 ? scale * PeakShape(peak) : spread / std::sqrt(2.0), kSincFloorSamples);
    // To the instants the reference pairs describe (header): lags in samples, rates in s/s.
    const double at_instants =
        peak.lag + 0.5 * (rate_of_node[static_cast<size_t>(b)] * lag_of_node[static_cast<size_t>(a)] -
                          rate_of_node[static_cast<size_t>(a)] * lag_of_node[static_cast<size_t>(b)]);
    edges_.push_back({a, b, at_instants, 1.0 / (sigma * sigma), true});
    ++report.cross_edges;
  }
  if (report.cross_edges == 0) return report;

  // At most kMaxNodes: fixed-capacity storage, nothing allocated per frame.
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxNodes, kMaxNodes>;
  using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxNodes, 1>;
  Matrix normal(nodes, nodes);
  Vector rhs(nodes), x(nodes);
  Eigen::LDLT<Matrix> solver(nodes);
  std::array<char, kMaxNodes> tied{};
  const auto residual = [&x](const Edge& e) { return e.d - (x(e.b) - (e.a >= 0 ? x(e.a) : 0.0)); };
  for (int round = 0; round < 4; ++round) {
    normal.setZero();
    rhs.setZero();
    for (const Edge& e : edges_) {
      if (!e.kept) continue;
      normal(e.b, e.b) += e.w;
      rhs(e.b) += e.w * e.d;
      if (e.a >= 0) {
        normal(e.a, e.a) += e.w;
        normal(e.a, e.b) -= e.w;
        normal(e.b, e.a) -= e.w;
        rhs(e.a) -= e.w * e.d;
      }
    }
    // A node left without its reference edge is still tied through cross pairs; one with no
    // edge at all keeps its measured delay.
    for (int k = 0; k < nodes; ++k) {
      tied[static_cast<size_t>(k)] = normal(k, k) > 0.0;
      if (!tied[static_cast<size_t>(k)]) {
        normal(k, k) = 1.0;
        rhs(k) = lag_of_node[static_cast<size_t>(k)];
      }
    }
    solver.compute(normal);
    if (solver.info() != Eigen::Success || !(solver.vectorD().array() > 0.0).all()) return FusionReport{};
    x = solver.solve(rhs);
    if (round == 3) break;
    bool dropped = false;
    for (Edge& e : edges_) {
      if (!e.kept) continue;
      if (std::abs(residual(e)) * std::sqrt(e.w) > kOutlierSigmas) {
        e.kept = false;
        dropped = true;
        ++report.dropped_edges;
      }
    }
    if (!dropped) break;
  }
  // How much of the pairs' error closes (header): chi^2 per degree of freedom of the kept edges,
  // averaged over frames.
  double chi2 = 0.0;
  int kept = 0;
  for (const Edge& e : edges_) {
    if (!e.kept) continue;
    const double r = residual(e);
    chi2 += e.w * r * r;
    ++kept;
  }
  if (kept > nodes) {
    const double frame_share = std::clamp(chi2 / (kept - nodes), 0.0, 1.0);
    independent_share_ =
        frames_ == 0 ? frame_share : independent_share_ + kShareSmoothing * (frame_share - independent_share_);
    ++frames_;
  }
  report.independent_share = independent_share_;
  const Matrix covariance = solver.solve(Matrix::Identity(nodes, nodes));
  for (int k = 0; k < nodes; ++k) {
    const double own_var = sigma_of_node[static_cast<size_t>(k)] * sigma_of_node[static_cast<size_t>(k)];
    const double var = independent_share_ * covariance(k, k) + (1.0 - independent_share_) * own_var;
    if (!tied[static_cast<size_t>(k)] || !std::isfinite(x(k)) || !(var > 0.0) || !std::isfinite(var)) continue;
    PairMeasurement& pm = m->pairs[static_cast<size_t>(pair_of_node_[static_cast<size_t>(k)])];
    pm.delay_s = x(k) / fs;
    pm.delay_sigma_s = std::sqrt(var) / fs;
    if (!pm.candidates.empty()) {
      pm.candidates[0].delay_s = pm.delay_s;
      pm.candidates[0].delay_sigma_s = pm.delay_sigma_s;
    }
    ++report.fused_pairs;
  }
  return report;
}

}  // namespace localizer::engine
