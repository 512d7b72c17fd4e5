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
//             exact test;
//   cluster   the gate graph (tracks and measurements as nodes, admissible pairs as edges)
//             falls into connected components (clustering.h), each solved alone;
//   assign    per component, the one-to-one matching minimising the total of d^2 over
//             matched pairs plus g per unmatched track (assignment.h SolveGnn): a
//             measurement inside the gate is always preferred to a miss. A component of one
//             track takes its nearest measurement (d^2).
// assigned[i] is the measurement index for track i, or -1; the measurements given out are
// marked taken (taken()), so a later call (tentative tracks after confirmed ones) sees only
// what is left. stats accumulates the components with at least one edge and the tracks in
// the largest.
// Deterministic: ties resolve by index order. Work arrays persist between scans (no
// allocation once grown). The measurement vector must outlive the scan's calls. Not
// thread-safe; one per tracker.
//
// Cost per call: O(T + M) plus the exact tests of the measurements inside each track's box,
// plus the assignment of each multi-track component (cubic in its size; small unless
// targets crowd).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "engine/tws/assignment.h"
#include "engine/tws/clustering.h"
#include "engine/tws/gaussian.h"
#include "engine/tws/point_grid.h"

namespace localizer::engine::tws {

struct AssociationStats {
  int clusters = 0;         // gate-graph components with >= 1 edge, over the scan's calls
  int largest_cluster = 0;  // tracks in the largest of them
};

template <int D>
class GnnAssociator {
 public:
  // gate_threshold: g > 0, on d^2.
  explicit GnnAssociator(double gate_threshold) : gate_(gate_threshold) {}

  void BeginScan(const std::vector<Gaussian<D>>& measurements);
  void Associate(const std::vector<Gaussian<D>>& expected, std::vector<int>* assigned, AssociationStats* stats);

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

  double gate_;
  const std::vector<Gaussian<D>>* measurements_ = nullptr;
  std::vector<Eigen::Vector2d> xy_;  // the measurements' first two coordinates, for the grid
  Eigen::Matrix<double, D, 1> max_r_diag_;
  std::vector<char> taken_;
  PointGrid grid_;
  std::vector<Edge> edges_, sorted_edges_;
  UnionFind uf_;
  std::vector<int> cluster_of_root_, cluster_start_, edge_cluster_, fill_, local_index_;
  std::vector<int> rows_, cols_, col_for_row_;
  std::vector<double> cost_, miss_;
  AssignmentSolver solver_;
};

}  // namespace localizer::engine::tws
