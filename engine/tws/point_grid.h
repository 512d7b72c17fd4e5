// A uniform grid over 2-D points (x, y) for the gate's coarse test: a track asks for the
// points inside an axis-aligned box around its predicted position, and only those get the
// exact chi^2 test. Built by a counting sort: O(n + cells) per build, cells ~ n (the
// bounding box of the points cut into squares of about one point each, at most 4n + 16
// cells). A box query visits the cells it overlaps; QueryWithin caps that work. Arrays are kept between builds (no
// allocation once grown). Not thread-safe.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace localizer::engine::tws {

class PointGrid {
 public:
  void Build(const std::vector<Eigen::Vector2d>& points);

  // Calls visit(i) for every point i with x in [x0, x1] and y in [y0, y1].
  template <typename Visit>
  void Query(double x0, double x1, double y0, double y1, Visit&& visit) const {
    QueryWithin(x0, x1, y0, y1, std::numeric_limits<int64_t>::max(), visit);
  }

  // The same, spending at most `budget` units of work (one per cell row and one per point
  // looked at, inside the box or not): a box that an adversarial or cluttered scan fills
  // costs no more than the budget. Returns false when the budget ran out before the box was
  // searched (the points visited so far are a deterministic subset: row by row, cell order).
  template <typename Visit>
  bool QueryWithin(double x0, double x1, double y0, double y1, int64_t budget, Visit&& visit) const {
    if (count_ == 0 || x1 < min_x_ || y1 < min_y_ || x0 > max_x_ || y0 > max_y_) return true;
    const int c0 = Cell(x0, min_x_, nx_), c1 = Cell(x1, min_x_, nx_);
    const int r0 = Cell(y0, min_y_, ny_), r1 = Cell(y1, min_y_, ny_);
    for (int r = r0; r <= r1; ++r) {
      if (--budget < 0) return false;
      const int begin = start_[r * nx_ + c0], end = start_[r * nx_ + c1 + 1];
      for (int k = begin; k < end; ++k) {
        if (--budget < 0) return false;
        const int i = items_[k];
        const Eigen::Vector2d& p = (*points_)[i];
        if (p.x() >= x0 && p.x() <= x1 && p.y() >= y0 && p.y() <= y1) visit(i);
      }
    }
    return true;
  }

 private:
  int Cell(double v, double lo, int n) const {
    const double c = std::floor((v - lo) * inverse_cell_);
    return static_cast<int>(std::clamp(c, 0.0, static_cast<double>(n - 1)));
  }

  const std::vector<Eigen::Vector2d>* points_ = nullptr;
  int count_ = 0;
  int nx_ = 1, ny_ = 1;
  double min_x_ = 0, min_y_ = 0, max_x_ = 0, max_y_ = 0, inverse_cell_ = 1;
  std::vector<int> start_;  // row-major cells; start_[c] .. start_[c + 1] in items_
  std::vector<int> items_;
  std::vector<int> cell_of_;
};

}  // namespace localizer::engine::tws
