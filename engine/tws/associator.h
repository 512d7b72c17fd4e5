// Associator: which measurement updates which track in one scan. Global nearest neighbour
// (GNN) with an ellipsoidal gate, solved per cluster (Stone Soup's hypothesiser and data
// associator roles).
//
// Contract. BeginScan(z) takes the scan's measurements z_j (mean, covariance R_j), none
// taken. Each Associate(expected, &assigned) call then matches tracks, given by what each
// expects to measure (mean zhat_i, covariance A_i; updater.h Expected), against the
// measurements no earlier call of the scan took:
//   gate      (i, j) is admissible when d^2 = nu^T (A_i + R_j)^-1 nu <= g, nu = z_j - zhat_i,
//             g the gate threshold (chi_square.h: the chi^2_D quantile of the gate
//             probability); a box test on the first two coordinates (point_grid.h) and a
//             per-axis bound come first, so that only measurements near a track get the
//             exact test. Each track's search spends at most limits.gate_search_budget units
//             (PointGrid::QueryWithin); a track whose box holds more keeps the edges found
//             so far (stats: truncated_gates) -- in such clutter GNN cannot choose anyway,
//             and an adversarial scan of co-located plots costs O(T budget), not O(T M);
//   cluster   the gate graph (tracks and measurements as nodes, admissible pairs as edges)
//             falls into connected components (clustering.h), each solved alone;
//   assign    per component, the one-to-one matching minimising the total of d^2 over
//             matched pairs plus g per unmatched track (assignment.h SolveGnn): a
//             measurement inside the gate is always preferred to a miss. A component of one
//             track takes its nearest measurement (d^2). A component whose tracks x
//             measurements exceed limits.max_assignment_cells is matched greedily instead
//             (pairs in order of d^2, ties by index, each taken when both ends are free;
//             stats: greedy_clusters): its cost is O(E log E) in its edges, not cubic.
// assigned[i] is the measurement index for track i, or -1; the measurements given out are
// marked taken (taken()), so a later call (tentative tracks after confirmed ones) sees only
// what is left. stats accumulates the components with at least one edge and the tracks in
// the largest.
// Deterministic: ties resolve by index order. Work arrays persist between scans (no
// allocation once grown). The measurement vector must outlive the scan's calls. Not
// thread-safe; one per tracker.
//
// Cost per call: O(T + M) plus the exact tests of the measurements inside each track's box
// (at most the budget per track), plus the assignment of each multi-track component (cubic
// in its size, bounded by max_assignment_cells; greedy beyond). Memory: edges <= T budget.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "engine/tws/assignment.h"
#include "engine/tws/clustering.h"
#include "engine/tws/gaussian.h"
#include "engine/tws/point_grid.h"

namespace localizer::engine::tws {

struct AssociationStats {
  int clusters = 0;         // gate-graph components with >= 1 edge, over the scan's calls
  int largest_cluster = 0;  // tracks in the largest of them
  int truncated_gates = 0;  // tracks whose gate search ran out of budget
  int greedy_clusters = 0;  // components matched greedily (too large for the optimal solver)
};

// Bounds on one scan's association work (tws_options.h has the defaults and their reasons).
struct AssociatorLimits {
  int64_t gate_search_budget = 64;       // per track: grid rows + measurements looked at
  int64_t max_assignment_cells = 65536;  // tracks x measurements of a component solved optimally
};

template <int D>
class GnnAssociator {
 public:
  // gate_threshold: g > 0, on d^2.
  explicit GnnAssociator(double gate_threshold, const AssociatorLimits& limits = {})
      : gate_(gate_threshold), limits_(limits) {}

  void BeginScan(const std::vector<Gaussian<D>>& measurements);
  void Associate(const std::vector<Gaussian<D>>& expected, std::vector<int>* assigned, AssociationStats* stats);

  // Measurements the next Associate calls must not give out (1 = withheld; null: none), for
  // tracks that may take only some of the scan's plots. Not owned; reset by BeginScan.
  void Withhold(const std::vector<char>* withheld) { withheld_ = withheld; }

  // Per measurement of the scan: 1 when a track took it.
  const std::vector<char>& taken() const { return taken_; }
  double gate_threshold() const { return gate_; }

 private:
  struct Edge {
    int track;  // index into `expected`
    int measurement;
    double d2;
  };
  void SolveCluster(const Edge* begin, const Edge* end, int n_tracks, std::vector<int>* assigned,
                    AssociationStats* stats);

  void SolveGreedy(const Edge* begin, const Edge* end, std::vector<int>* assigned);

  double gate_;
  AssociatorLimits limits_;
  const std::vector<Gaussian<D>>* measurements_ = nullptr;
  std::vector<Eigen::Vector2d> xy_;  // the measurements' first two coordinates, for the grid
  Eigen::Matrix<double, D, 1> max_r_diag_;
  std::vector<char> taken_;
  const std::vector<char>* withheld_ = nullptr;
  PointGrid grid_;
  std::vector<Edge> edges_, sorted_edges_, greedy_edges_;
  UnionFind uf_;
  std::vector<int> cluster_of_root_, cluster_start_, edge_cluster_, fill_, local_index_;
  std::vector<int> rows_, cols_, col_for_row_;
  std::vector<double> cost_, miss_;
  AssignmentSolver solver_;
};

}  // namespace localizer::engine::tws
