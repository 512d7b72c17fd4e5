// The assignment solver against brute force on small random problems: square,
// rectangular, with forbidden entries, and the GNN form with misses.
#include "engine/tws/assignment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <random>
#include <vector>

namespace localizer::engine::tws {
namespace {

// Minimum over one-to-one maps rows -> columns avoiding forbidden entries; +inf if none.
double BruteForce(const std::vector<double>& cost, int rows, int cols) {
  std::vector<char> used(cols, 0);
  double best = kForbidden;
  std::function<void(int, double)> go = [&](int i, double total) {
    if (i == rows) {
      best = std::min(best, total);
      return;
    }
    for (int j = 0; j < cols; ++j) {
      const double c = cost[i * cols + j];
      if (used[j] || c == kForbidden) continue;
      used[j] = 1;
      go(i + 1, total + c);
      used[j] = 0;
    }
  };
  go(0, 0.0);
  return best;
}

// Minimum over partial maps, an unassigned row costing miss[i].
double BruteForceGnn(const std::vector<double>& cost, int rows, int cols, const std::vector<double>& miss) {
  std::vector<char> used(cols, 0);
  double best = kForbidden;
  std::function<void(int, double)> go = [&](int i, double total) {
    if (i == rows) {
      best = std::min(best, total);
      return;
    }
    go(i + 1, total + miss[i]);
    for (int j = 0; j < cols; ++j) {
      const double c = cost[i * cols + j];
      if (used[j] || c == kForbidden) continue;
      used[j] = 1;
      go(i + 1, total + c);
      used[j] = 0;
    }
  };
  go(0, 0.0);
  return best;
}

std::vector<double> RandomCost(std::mt19937_64& engine, int rows, int cols, double forbidden_fraction) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int> small(0, 4);  // ties are common with integer costs
  std::vector<double> cost(rows * cols);
  for (double& c : cost) {
    c = u(engine) < forbidden_fraction ? kForbidden : (u(engine) < 0.5 ? small(engine) : 10.0 * u(engine));
  }
  return cost;
}

TEST(Assignment, EqualsBruteForceOnRandomRectangularProblemsWithForbiddenEntries) {
  std::mt19937_64 engine(20261122);
  std::uniform_int_distribution<int> size(1, 6);
  AssignmentSolver solver;
  int feasible = 0, infeasible = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    int rows = size(engine), cols = size(engine);
    if (rows > cols) std::swap(rows, cols);
    const double forbidden = (trial % 3) * 0.3;  // 0, 0.3, 0.6
    const std::vector<double> cost = RandomCost(engine, rows, cols, forbidden);
    std::vector<int> col(rows, -2);
    const bool ok = solver.Solve(cost.data(), rows, cols, col.data());
    const double best = BruteForce(cost, rows, cols);
    ASSERT_EQ(ok, best < kForbidden) << "trial " << trial;
    if (!ok) {
      ++infeasible;
      continue;
    }
    ++feasible;
    double total = 0.0;
    std::vector<char> used(cols, 0);
    for (int i = 0; i < rows; ++i) {
      ASSERT_GE(col[i], 0);
      ASSERT_LT(col[i], cols);
      ASSERT_FALSE(used[col[i]]) << "column used twice";
      used[col[i]] = 1;
      ASSERT_NE(cost[i * cols + col[i]], kForbidden);
      total += cost[i * cols + col[i]];
    }
    ASSERT_NEAR(total, best, 1e-9) << "trial " << trial << " " << rows << "x" << cols;
  }
  EXPECT_GT(feasible, 1000);
  EXPECT_GT(infeasible, 100);  // the infeasible branch was exercised
}

TEST(Assignment, MoreRowsThanColumnsIsInfeasible) {
  AssignmentSolver solver;
  const std::vector<double> cost = {1.0, 2.0, 3.0};
  std::vector<int> col(3);
  EXPECT_FALSE(solver.Solve(cost.data(), 3, 1, col.data()));
}

TEST(Assignment, GnnWithMissesEqualsBruteForceInAnyShape) {
  std::mt19937_64 engine(7);
  std::uniform_int_distribution<int> size(1, 6);
  std::uniform_real_distribution<double> u(0.0, 8.0);
  AssignmentSolver solver;
  int some_missed = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const int rows = size(engine), cols = size(engine);  // rows > cols allowed
    const std::vector<double> cost = RandomCost(engine, rows, cols, (trial % 3) * 0.3);
    std::vector<double> miss(rows);
    for (double& m : miss) m = u(engine);
    std::vector<int> col(rows, -2);
    solver.SolveGnn(cost.data(), rows, cols, miss.data(), col.data());
    double total = 0.0;
    std::vector<char> used(cols, 0);
    bool missed = false;
    for (int i = 0; i < rows; ++i) {
      if (col[i] < 0) {
        ASSERT_EQ(col[i], -1);
        total += miss[i];
        missed = true;
        continue;
      }
      ASSERT_LT(col[i], cols);
      ASSERT_FALSE(used[col[i]]);
      used[col[i]] = 1;
      ASSERT_NE(cost[i * cols + col[i]], kForbidden);
      total += cost[i * cols + col[i]];
    }
    some_missed += missed;
    ASSERT_NEAR(total, BruteForceGnn(cost, rows, cols, miss), 1e-9) << "trial " << trial;
  }
  EXPECT_GT(some_missed, 500);
}

TEST(Assignment, GlobalBeatsGreedyOnTheClassicExample) {
  // Greedy nearest neighbour takes (0, 0) at cost 1 and must then pay 10 for (1, 1);
  // the optimum crosses: 2 + 2.
  const std::vector<double> cost = {1.0, 2.0, 2.0, 10.0};
  std::vector<int> col(2);
  AssignmentSolver solver;
  ASSERT_TRUE(solver.Solve(cost.data(), 2, 2, col.data()));
  EXPECT_EQ(col[0], 1);
  EXPECT_EQ(col[1], 0);
}

}  // namespace
}  // namespace localizer::engine::tws
