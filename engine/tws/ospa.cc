#include "engine/tws/ospa.h"

#include <algorithm>
#include <cmath>

#include "engine/tws/assignment.h"

namespace localizer::engine::tws {

double Ospa(const std::vector<Eigen::Vector3d>& truth, const std::vector<Eigen::Vector3d>& estimates, double cutoff,
            double order) {
  const bool swap = truth.size() > estimates.size();
  const auto& small = swap ? estimates : truth;
  const auto& large = swap ? truth : estimates;
  const int m = static_cast<int>(small.size()), n = static_cast<int>(large.size());
  if (n == 0) return 0.0;
  const double cp = std::pow(cutoff, order);
  double total = cp * (n - m);
  if (m > 0) {
    std::vector<double> cost(static_cast<size_t>(m) * n);
    for (int i = 0; i < m; ++i) {
      for (int j = 0; j < n; ++j) {
        cost[static_cast<size_t>(i) * n + j] = std::pow(std::min(cutoff, (small[i] - large[j]).norm()), order);
      }
    }
    std::vector<int> col(m);
    AssignmentSolver solver;
    solver.Solve(cost.data(), m, n, col.data());  // always feasible: no forbidden entry
    for (int i = 0; i < m; ++i) total += cost[static_cast<size_t>(i) * n + col[i]];
  }
  return std::pow(total / n, 1.0 / order);
}

GospaResult Gospa(const std::vector<Eigen::Vector3d>& truth, const std::vector<Eigen::Vector3d>& estimates,
                  double cutoff, double order) {
  const int m = static_cast<int>(truth.size()), n = static_cast<int>(estimates.size());
  const double cp = std::pow(cutoff, order);
  GospaResult r;
  if (m > 0 && n > 0) {
    // Rows truths, columns estimates; a missed row costs c^p, which with the constant
    // c^p/2 (n - m) gives the c^p/2 per unassigned truth and per unassigned estimate.
    std::vector<double> cost(static_cast<size_t>(m) * n, kForbidden);
    for (int i = 0; i < m; ++i) {
      for (int j = 0; j < n; ++j) {
        const double d = (truth[i] - estimates[j]).norm();
        if (d < cutoff) cost[static_cast<size_t>(i) * n + j] = std::pow(d, order);
      }
    }
    std::vector<double> miss(m, cp);
    std::vector<int> col(m);
    AssignmentSolver solver;
    solver.SolveGnn(cost.data(), m, n, miss.data(), col.data());
    for (int i = 0; i < m; ++i) {
      if (col[i] < 0) continue;
      r.localisation += cost[static_cast<size_t>(i) * n + col[i]];
      ++r.assigned;
    }
  }
  r.missed = m - r.assigned;
  r.false_tracks = n - r.assigned;
  r.gospa = std::pow(r.localisation + 0.5 * cp * (r.missed + r.false_tracks), 1.0 / order);
  return r;
}

}  // namespace localizer::engine::tws
