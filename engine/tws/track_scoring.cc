#include "engine/tws/track_scoring.h"

#include <algorithm>

#include "engine/tws/assignment.h"

namespace localizer::engine::tws {

void TrackScoring::Add(const std::vector<Labelled>& truth, const std::vector<Labelled>& tracks) {
  const int m = static_cast<int>(truth.size()), n = static_cast<int>(tracks.size());
  if (m == 0 || n == 0) return;
  const double gate = max_distance_m_ * max_distance_m_;
  // Step 1: keep last scan's pairs that are still valid.
  std::vector<int> kept(m, -1);
  std::vector<char> track_taken(n, 0);
  for (int i = 0; i < m; ++i) {
    const auto last = last_track_of_truth_.find(truth[i].id);
    if (last == last_track_of_truth_.end()) continue;
    for (int j = 0; j < n; ++j) {
      if (tracks[j].id == last->second && !track_taken[j] &&
          (truth[i].position_m - tracks[j].position_m).squaredNorm() <= gate) {
        kept[i] = j;
        track_taken[j] = 1;
        break;
      }
    }
  }
  // Step 2: the rest by assignment.
  std::vector<double> cost(static_cast<size_t>(m) * n, kForbidden);
  for (int i = 0; i < m; ++i) {
    if (kept[i] >= 0) continue;
    for (int j = 0; j < n; ++j) {
      if (track_taken[j]) continue;
      const double d2 = (truth[i].position_m - tracks[j].position_m).squaredNorm();
      if (d2 <= gate) cost[static_cast<size_t>(i) * n + j] = d2;
    }
  }
  std::vector<double> miss(m, gate);
  std::vector<int> col(m);
  AssignmentSolver solver;
  solver.SolveGnn(cost.data(), m, n, miss.data(), col.data());
  for (int i = 0; i < m; ++i) {
    if (kept[i] >= 0) col[i] = kept[i];
    if (col[i] < 0) continue;
    const uint64_t track = tracks[col[i]].id;
    auto [it, inserted] = last_track_of_truth_.emplace(truth[i].id, track);
    if (!inserted && it->second != track) {
      ++switches_;
      it->second = track;
    }
    ++counts_[track][truth[i].id];
    ++paired_;
  }
}

double TrackScoring::Purity() const {
  if (paired_ == 0) return 1.0;
  int64_t best_total = 0;
  for (const auto& [track, by_truth] : counts_) {
    int64_t best = 0;
    for (const auto& [truth, count] : by_truth) best = std::max(best, count);
    best_total += best;
  }
  return static_cast<double>(best_total) / static_cast<double>(paired_);
}

}  // namespace localizer::engine::tws
