#include "engine/tws/initiator.h"

#include <algorithm>
#include <cmath>

namespace localizer::engine::tws {

template <int D>
void Initiator<D>::Start(const State& x, const Cov& p, int hits, std::vector<Started>* started) const {
  Started s;
  s.x = x;
  s.p = p;
  s.history.age = hits;
  s.history.hits = hits;
  s.history.bits = hits >= 2 ? 3u : 1u;
  s.history.confirmed = rule_.Reached(s.history);
  started->push_back(s);
}

template <int D>
void Initiator<D>::Initiate(const std::vector<Gaussian<D>>& measurements, const std::vector<char>& taken, double dt,
                            int room, std::vector<Started>* started) {
  using Pos = typename Cv<D>::Pos;
  using PosCov = typename Cv<D>::PosCov;
  started->clear();
  int count = 0;
  if (options_.method == Initiation::kOnePoint) {
    for (size_t j = 0; j < measurements.size() && count < room; ++j) {
      if (taken[j]) continue;
      State x = State::Zero();
      x.template head<D>() = measurements[j].mean;
      Cov p = Cov::Zero();
      p.template topLeftCorner<D, D>() = measurements[j].covariance;
      p.template bottomRightCorner<D, D>() =
          PosCov::Identity() * options_.initial_speed_sigma_mps * options_.initial_speed_sigma_mps;
      Start(x, p, 1, started);
      ++count;
    }
    return;
  }
  // Two-point: pair each free measurement with the nearest free one of the previous scan
  // within max_speed dt (plus 3 sigma of both); the rest wait for the next scan.
  candidate_grid_.Build(candidate_xy_);
  candidate_used_.assign(candidates_.size(), 0);
  next_candidates_.clear();
  for (size_t j = 0; j < measurements.size(); ++j) {
    if (taken[j]) continue;
    const Gaussian<D>& second = measurements[j];
    int best = -1;
    double best_d2 = 0.0;
    if (dt > 0.0 && !candidates_.empty() && count < room) {
      const double reach =
          options_.max_speed_mps * dt + 3.0 * std::sqrt(second.covariance.trace() + max_candidate_r_trace_);
      const Pos z = second.mean;
      const auto consider = [&](int c) {
        if (candidate_used_[c]) return;
        const double d2 = (candidates_[c].mean - z).squaredNorm();
        if (d2 <= reach * reach && (best < 0 || d2 < best_d2)) {
          best = c;
          best_d2 = d2;
        }
      };
      candidate_grid_.QueryWithin(z(0) - reach, z(0) + reach, z(1) - reach, z(1) + reach, options_.search_budget,
                                  consider);
    }
    if (best < 0) {
      next_candidates_.push_back(second);
      continue;
    }
    candidate_used_[best] = 1;
    const Gaussian<D>& first = candidates_[best];
    State x;
    x.template head<D>() = second.mean;
    x.template tail<D>() = (second.mean - first.mean) / dt;
    Cov p;
    p.template topLeftCorner<D, D>() = second.covariance;
    p.template topRightCorner<D, D>() = second.covariance / dt;
    p.template bottomLeftCorner<D, D>() = second.covariance / dt;
    p.template bottomRightCorner<D, D>() = (second.covariance + first.covariance) / (dt * dt);
    Start(x, p, 2, started);
    ++count;
  }
  candidates_.swap(next_candidates_);
  candidate_xy_.resize(candidates_.size());
  max_candidate_r_trace_ = 0.0;
  for (size_t c = 0; c < candidates_.size(); ++c) {
    candidate_xy_[c] = candidates_[c].mean.template head<2>();
    max_candidate_r_trace_ = std::max(max_candidate_r_trace_, candidates_[c].covariance.trace());
  }
}

template class Initiator<2>;
template class Initiator<3>;

}  // namespace localizer::engine::tws
