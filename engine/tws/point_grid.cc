#include "engine/tws/point_grid.h"

namespace localizer::engine::tws {

void PointGrid::Build(const std::vector<Eigen::Vector2d>& points) {
  points_ = &points;
  count_ = static_cast<int>(points.size());
  if (count_ == 0) return;
  min_x_ = max_x_ = points[0].x();
  min_y_ = max_y_ = points[0].y();
  for (const Eigen::Vector2d& p : points) {
    min_x_ = std::min(min_x_, p.x());
    max_x_ = std::max(max_x_, p.x());
    min_y_ = std::min(min_y_, p.y());
    max_y_ = std::max(max_y_, p.y());
  }
  const double w = std::max(max_x_ - min_x_, 1e-9), h = std::max(max_y_ - min_y_, 1e-9);
  // Square cells holding about one point each when the points are spread evenly.
  const double cell = std::max(std::sqrt(w * h / count_), std::max(w, h) / (4.0 * count_ + 16));
  inverse_cell_ = 1.0 / cell;
  nx_ = std::min(static_cast<int>(w * inverse_cell_) + 1, 4 * count_ + 16);
  ny_ = std::min(static_cast<int>(h * inverse_cell_) + 1, 4 * count_ + 16);
  while (static_cast<long>(nx_) * ny_ > 4L * count_ + 16) {  // a long thin box
    inverse_cell_ *= 0.5;
    nx_ = static_cast<int>(w * inverse_cell_) + 1;
    ny_ = static_cast<int>(h * inverse_cell_) + 1;
  }
  start_.assign(static_cast<size_t>(nx_) * ny_ + 1, 0);
  cell_of_.resize(count_);
  for (int i = 0; i < count_; ++i) {
    const int c = Cell(points[i].y(), min_y_, ny_) * nx_ + Cell(points[i].x(), min_x_, nx_);
    cell_of_[i] = c;
    ++start_[c + 1];
  }
  for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  items_.resize(count_);
  // Fill from the back so that start_[c] ends as the beginning of cell c.
  for (int i = count_ - 1; i >= 0; --i) items_[--start_[cell_of_[i] + 1]] = i;
  // Now start_[c + 1] holds the beginning of cell c; shift back by one.
  for (size_t c = 0; c + 1 < start_.size(); ++c) start_[c] = start_[c + 1];
  start_.back() = count_;
}

}  // namespace localizer::engine::tws
