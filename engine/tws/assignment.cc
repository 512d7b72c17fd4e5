#include "engine/tws/assignment.h"

#include <algorithm>
#include <utility>

namespace localizer::engine::tws {

bool AssignmentSolver::Solve(const double* cost, int rows, int cols, int* col_for_row) {
  if (rows > cols) return false;
  u_.assign(rows, 0.0);
  v_.assign(cols, 0.0);
  col4row_.assign(rows, -1);
  row4col_.assign(cols, -1);
  shortest_.resize(cols);
  path_.resize(cols);
  remaining_.resize(cols);
  visited_row_.resize(rows);
  visited_col_.resize(cols);
  for (int current = 0; current < rows; ++current) {
    std::fill(shortest_.begin(), shortest_.end(), kForbidden);
    std::fill(path_.begin(), path_.end(), -1);
    std::fill(visited_row_.begin(), visited_row_.end(), 0);
    std::fill(visited_col_.begin(), visited_col_.end(), 0);
    int n_remaining = cols;
    for (int j = 0; j < cols; ++j) remaining_[j] = cols - 1 - j;
    double min_value = 0.0;
    int i = current;
    int sink = -1;
    while (sink < 0) {
      visited_row_[i] = 1;
      int index = -1;
      double lowest = kForbidden;
      const double* row = cost + static_cast<long>(i) * cols;
      for (int it = 0; it < n_remaining; ++it) {
        const int j = remaining_[it];
        const double reduced = min_value + row[j] - u_[i] - v_[j];
        if (reduced < shortest_[j]) {
          path_[j] = i;
          shortest_[j] = reduced;
        }
        // Ties go to an unassigned column: the path ends sooner.
        if (shortest_[j] < lowest || (shortest_[j] == lowest && lowest < kForbidden && row4col_[j] < 0)) {
          lowest = shortest_[j];
          index = it;
        }
      }
      if (index < 0 || !(lowest < kForbidden)) return false;  // every way out is forbidden
      min_value = lowest;
      const int j = remaining_[index];
      if (row4col_[j] < 0) {
        sink = j;
      } else {
        i = row4col_[j];
      }
      visited_col_[j] = 1;
      remaining_[index] = remaining_[--n_remaining];
    }
    // Dual update keeps reduced costs >= 0 on every allowed entry, 0 on the matching.
    u_[current] += min_value;
    for (int r = 0; r < rows; ++r) {
      if (visited_row_[r] && r != current) u_[r] += min_value - shortest_[col4row_[r]];
    }
    for (int c = 0; c < cols; ++c) {
      if (visited_col_[c]) v_[c] -= min_value - shortest_[c];
    }
    // Augment along the path back to the current row.
    int j = sink;
    while (true) {
      const int r = path_[j];
      row4col_[j] = r;
      std::swap(col4row_[r], j);
      if (r == current) break;
    }
  }
  std::copy(col4row_.begin(), col4row_.end(), col_for_row);
  return true;
}

void AssignmentSolver::SolveGnn(const double* cost, int rows, int cols, const double* miss_cost, int* col_for_row) {
  const int wide = cols + rows;
  augmented_.assign(static_cast<size_t>(rows) * wide, kForbidden);
  for (int i = 0; i < rows; ++i) {
    std::copy(cost + static_cast<long>(i) * cols, cost + static_cast<long>(i + 1) * cols,
              augmented_.begin() + static_cast<long>(i) * wide);
    augmented_[static_cast<size_t>(i) * wide + cols + i] = miss_cost[i];
  }
  const bool ok = Solve(augmented_.data(), rows, wide, col_for_row);
  for (int i = 0; i < rows; ++i) {
    if (!ok || col_for_row[i] >= cols) col_for_row[i] = -1;
  }
}

}  // namespace localizer::engine::tws
