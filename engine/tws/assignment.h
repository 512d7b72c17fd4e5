// Optimal assignment (the data associator's solver): minimum-cost matching of rows to
// columns, with forbidden entries.
//
// Solve(): rows <= cols, cost row-major (cost[i * cols + j]); an entry of +infinity is
// forbidden. Finds col_for_row minimising sum_i cost(i, col_for_row[i]) over one-to-one
// maps of every row to a distinct column, none forbidden; returns false (and leaves
// col_for_row unspecified) when no such map exists.
// Method: shortest augmenting paths with dual potentials (Jonker & Volgenant 1987, in the
// rectangular form of Crouse 2016): one Dijkstra search over reduced costs per row, O(n^2 m)
// worst case for n rows and m columns; forbidden entries are skipped, so a row whose every
// path is forbidden stops the search at once.
//
// SolveGnn(): global nearest neighbour with misses. Each row (track) either takes a
// distinct column (plot) at cost(i, j) or is missed at miss_cost[i] (finite); minimises the
// total. Built on Solve() with the matrix [cost | M], M = diag(miss_cost) and +inf off the
// diagonal: always feasible. col_for_row[i] = -1 for a missed row. Any rows/cols shape.
//
// The solver keeps its work arrays between calls (no allocation once they have grown).
// Not thread-safe; one per tracker.
#pragma once

#include <limits>
#include <vector>

namespace localizer::engine::tws {

inline constexpr double kForbidden = std::numeric_limits<double>::infinity();

class AssignmentSolver {
 public:
  bool Solve(const double* cost, int rows, int cols, int* col_for_row);
  void SolveGnn(const double* cost, int rows, int cols, const double* miss_cost, int* col_for_row);

 private:
  std::vector<double> u_, v_, shortest_, augmented_;
  std::vector<int> path_, col4row_, row4col_, remaining_;
  std::vector<char> visited_row_, visited_col_;
};

}  // namespace localizer::engine::tws
