#include "engine/tws/associator.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace localizer::engine::tws {

template <int D>
void GnnAssociator<D>::BeginScan(const std::vector<Gaussian<D>>& measurements) {
  measurements_ = &measurements;
  xy_.resize(measurements.size());
  max_r_diag_.setZero();
  for (size_t j = 0; j < measurements.size(); ++j) {
    xy_[j] = measurements[j].mean.template head<2>();
    max_r_diag_ = max_r_diag_.cwiseMax(measurements[j].covariance.diagonal());
  }
  grid_.Build(xy_);
  taken_.assign(measurements.size(), 0);
  withheld_ = nullptr;
}

template <int D>
void GnnAssociator<D>::Associate(const std::vector<Gaussian<D>>& expected, std::vector<int>* assigned,
                                 AssociationStats* stats) {
  using Pos = Eigen::Matrix<double, D, 1>;
  using PosCov = Eigen::Matrix<double, D, D>;
  const std::vector<Gaussian<D>>& measurements = *measurements_;
  const int n_tracks = static_cast<int>(expected.size());
  assigned->assign(n_tracks, -1);
  edges_.clear();
  for (int i = 0; i < n_tracks; ++i) {
    const Pos p = expected[i].mean;
    const PosCov a = expected[i].covariance;
    // Coarse: |nu_k| <= sqrt(g S_kk) is necessary for nu^T S^-1 nu <= g; bound S_kk by the
    // scan's largest R_kk.
    const double hx = std::sqrt(gate_ * (a(0, 0) + max_r_diag_(0)));
    const double hy = std::sqrt(gate_ * (a(1, 1) + max_r_diag_(1)));
    const auto test = [&](int j) {
      if (taken_[j] || (withheld_ != nullptr && (*withheld_)[j])) return;
      const Gaussian<D>& z = measurements[j];
      const PosCov sm = a + z.covariance;
      const Pos nu = z.mean - p;
      for (int k = 0; k < D; ++k) {
        if (nu(k) * nu(k) > gate_ * sm(k, k)) return;  // the exact per-axis bound
      }
      const double d2 = nu.dot(sm.inverse() * nu);
      if (d2 <= gate_) edges_.push_back({i, j, d2});
    };
    if (!grid_.QueryWithin(p(0) - hx, p(0) + hx, p(1) - hy, p(1) + hy, limits_.gate_search_budget, test)) {
      ++stats->truncated_gates;
    }
  }
  if (edges_.empty()) return;
  // Connected components: track nodes 0..n_tracks-1, measurement nodes n_tracks + j.
  const int n_measurements = static_cast<int>(measurements.size());
  uf_.Reset(n_tracks + n_measurements);
  for (const Edge& e : edges_) uf_.Union(e.track, n_tracks + e.measurement);
  cluster_of_root_.assign(n_tracks + n_measurements, -1);
  int n_clusters = 0;
  for (const Edge& e : edges_) {
    const int root = uf_.Find(e.track);
    if (cluster_of_root_[root] < 0) cluster_of_root_[root] = n_clusters++;
  }
  // Edges grouped by cluster (counting sort).
  cluster_start_.assign(n_clusters + 1, 0);
  edge_cluster_.resize(edges_.size());
  for (size_t k = 0; k < edges_.size(); ++k) {
    edge_cluster_[k] = cluster_of_root_[uf_.Find(edges_[k].track)];
    ++cluster_start_[edge_cluster_[k] + 1];
  }
  for (int c = 0; c < n_clusters; ++c) cluster_start_[c + 1] += cluster_start_[c];
  sorted_edges_.resize(edges_.size());
  fill_.assign(cluster_start_.begin(), cluster_start_.end() - 1);
  for (size_t k = 0; k < edges_.size(); ++k) sorted_edges_[fill_[edge_cluster_[k]]++] = edges_[k];
  stats->clusters += n_clusters;
  local_index_.assign(n_tracks + n_measurements, -1);
  for (int c = 0; c < n_clusters; ++c) {
    const Edge* begin = sorted_edges_.data() + cluster_start_[c];
    const Edge* end = sorted_edges_.data() + cluster_start_[c + 1];
    SolveCluster(begin, end, n_tracks, assigned, stats);
  }
}

template <int D>
void GnnAssociator<D>::SolveCluster(const Edge* begin, const Edge* end, int n_tracks, std::vector<int>* assigned,
                                    AssociationStats* stats) {
  const auto take = [&](int track, int measurement) {
    (*assigned)[track] = measurement;
    taken_[measurement] = 1;
  };
  rows_.clear();
  cols_.clear();
  for (const Edge* e = begin; e != end; ++e) {
    if (local_index_[e->track] < 0) {
      local_index_[e->track] = static_cast<int>(rows_.size());
      rows_.push_back(e->track);
    }
    if (local_index_[n_tracks + e->measurement] < 0) {
      local_index_[n_tracks + e->measurement] = static_cast<int>(cols_.size());
      cols_.push_back(e->measurement);
    }
  }
  stats->largest_cluster = std::max(stats->largest_cluster, static_cast<int>(rows_.size()));
  const int64_t cells = static_cast<int64_t>(rows_.size()) * static_cast<int64_t>(cols_.size());
  if (rows_.size() == 1) {  // every measurement of the cluster sees this track only
    const Edge* best = begin;
    for (const Edge* e = begin; e != end; ++e) {
      if (e->d2 < best->d2) best = e;
    }
    take(best->track, best->measurement);
  } else if (cells > limits_.max_assignment_cells) {
    ++stats->greedy_clusters;
    SolveGreedy(begin, end, assigned);
  } else {
    const int nr = static_cast<int>(rows_.size()), nc = static_cast<int>(cols_.size());
    cost_.assign(static_cast<size_t>(nr) * nc, kForbidden);
    for (const Edge* e = begin; e != end; ++e) {
      cost_[static_cast<size_t>(local_index_[e->track]) * nc + local_index_[n_tracks + e->measurement]] = e->d2;
    }
    miss_.assign(nr, gate_);
    col_for_row_.resize(nr);
    solver_.SolveGnn(cost_.data(), nr, nc, miss_.data(), col_for_row_.data());
    for (int r = 0; r < nr; ++r) {
      if (col_for_row_[r] >= 0) take(rows_[r], cols_[col_for_row_[r]]);
    }
  }
  for (int r : rows_) local_index_[r] = -1;
  for (int c : cols_) local_index_[n_tracks + c] = -1;
}

template <int D>
void GnnAssociator<D>::SolveGreedy(const Edge* begin, const Edge* end, std::vector<int>* assigned) {
  greedy_edges_.assign(begin, end);
  std::sort(greedy_edges_.begin(), greedy_edges_.end(), [](const Edge& a, const Edge& b) {
    if (a.d2 != b.d2) return a.d2 < b.d2;
    if (a.track != b.track) return a.track < b.track;
    return a.measurement < b.measurement;
  });
  for (const Edge& e : greedy_edges_) {
    if ((*assigned)[e.track] >= 0 || taken_[e.measurement]) continue;
    (*assigned)[e.track] = e.measurement;
    taken_[e.measurement] = 1;
  }
}

template class GnnAssociator<2>;
template class GnnAssociator<3>;

}  // namespace localizer::engine::tws
