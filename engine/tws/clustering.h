// Clustering of the gate graph: tracks and plots are nodes, a (track, plot) pair inside the
// gate is an edge; each connected component is an independent assignment problem, solved
// alone (a 1000-target scene is mostly 1-track clusters, so the optimal assignment costs
// about what nearest neighbour would).
//
// Union-find with path halving and union by size: near-constant time per edge. Reset(n)
// reuses the arrays (no allocation once grown). Not thread-safe.
#pragma once

#include <utility>
#include <vector>

namespace localizer::engine::tws {

class UnionFind {
 public:
  void Reset(int nodes) {
    parent_.resize(nodes);
    size_.assign(nodes, 1);
    for (int i = 0; i < nodes; ++i) parent_[i] = i;
  }
  int Find(int x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  void Union(int a, int b) {
    a = Find(a);
    b = Find(b);
    if (a == b) return;
    if (size_[a] < size_[b]) std::swap(a, b);
    parent_[b] = a;
    size_[a] += size_[b];
  }

 private:
  std::vector<int> parent_;
  std::vector<int> size_;
};

}  // namespace localizer::engine::tws
