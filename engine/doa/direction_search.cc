// SrpPhat's per-frame work (srp_phat.h): the branch-and-bound search, the refinement on the
// exact spectrum, the removal of each source found and the description of a peak.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <queue>

#include "engine/doa/srp_phat.h"

namespace localizer::engine {
namespace {
constexpr int kRefineIterations = 8;  // Newton takes 3-4 on a peak
constexpr int kHalvings = 3;
constexpr double kConverged_rad = 1e-5;  // far below any array's direction bound
constexpr int kReestimations = 2;
// Search starts closer than this to an end point already reached are not refined (about
// three root radii of the 8192 roots).
constexpr double kSameStartRad = 0.12;

}  // namespace

double SrpPhat::Apart(const Cell& a, const Cell& b) const {
  if (linear()) return std::abs(a.theta_rad - b.theta_rad);
  return std::atan2(a.u.cross(b.u).norm(), a.u.dot(b.u));
}

bool SrpPhat::Search(Cell* best) {
  starts_.clear();
  const std::vector<Cell>& roots = roots_;
  if (!roots.empty() && Leaf(roots.front())) {  // a plain grid: every root is a leaf
    double best_value = -std::numeric_limits<double>::infinity();
    // Every pair usable (PairSpectra's fields always are): the precomputed taps, else LagField::At.
    const bool taps = field_.usable_pairs() == pair_count() && GridCentres();
    const double root_pairs = std::sqrt(static_cast<double>(pair_count()));
    for (size_t r = 0; r < roots.size(); ++r) {
      const double value = taps ? grid_sums_[r] / root_pairs : Centre(roots[r]);
      if (value > best_value) {
        best_value = value;
        *best = roots[r];
      }
    }
    return !roots.empty();
  }
  auto lower = [](const Cell& a, const Cell& b) { return a.bound < b.bound; };
  std::priority_queue<Cell, std::vector<Cell>, decltype(lower)> open(lower);
  for (Cell c : roots) {  // a copy: the bound is this frame's
    c.bound = Bound(c);
    open.push(c);
  }
  double best_value = -std::numeric_limits<double>::infinity();
  bool found = false;
  int bounded = static_cast<int>(open.size());
  std::vector<Cell> children;
  while (!open.empty() && bounded < options_.cell_budget) {
    const Cell top = open.top();
    if (top.bound <= best_value) break;  // no open cell can beat the best leaf
    open.pop();
    if (Leaf(top)) {
      const double value = Centre(top);
      if (value > best_value) {
        best_value = value;
        *best = top;
        found = true;
      }
      continue;
    }
    Split(top, &children);
    for (Cell& c : children) {
      c.bound = Bound(c);
      open.push(c);
      ++bounded;
    }
  }
  if (!found && !open.empty()) {  // out of budget before any leaf: the most promising cell
    *best = open.top();
    found = true;
    open.pop();
    while (!open.empty() && static_cast<int>(starts_.size()) + 1 < options_.search_starts) {
      starts_.push_back(open.top());
      open.pop();
    }
  }
  return found;
}

double SrpPhat::FieldCeiling() const {
  double sum = 0.0;
  for (int p = 0; p < pair_count(); ++p) {
    if (!field_.usable(p)) continue;
    const double first = field_.first_lag(p), last = field_.last_lag(p);
    sum += std::max(0.0, field_.MaxAround(p, 0.5 * (first + last), 0.5 * (last - first)));
  }
  return interpolation_margin_ * sum / std::sqrt(static_cast<double>(pair_count()));
}

double SrpPhat::Exact(const Cell& cell) const {
  double sum = 0.0;
  for (int p = 0; p < pair_count(); ++p) sum += spectra_.At(p, Lag(p, cell)).r;
  return sum / spectra_.noise_sigma() / std::sqrt(static_cast<double>(pair_count()));
}

double SrpPhat::Whole(const Cell& cell, bool previous) const {
  double sum = 0.0;
  for (int p = 0; p < pair_count(); ++p) sum += spectra_.WholeAt(p, Lag(p, cell), previous);
  return sum / spectra_.noise_sigma() / std::sqrt(static_cast<double>(pair_count()));
}

// The spectrum's sum over pairs at a cell's centre with its gradient and Hessian in the
// refinement's coordinates (one pass over the bins). Arcs: theta (the 1 x 1 corner).
// Sphere: the tangent plane at u. Planar arrays: the array plane, on the direction's
// in-plane part w (lags are linear in w, u = w + sqrt(1 - |w|^2) n); on the sphere, the
// plane's mirror symmetry makes every in-plane direction a stationary point in elevation,
// where Newton would stop.
SrpPhat::Probe SrpPhat::ProbeAt(const Cell& cell) const {
  Probe out;
  if (linear()) {
    const double c = std::cos(cell.theta_rad), s = std::sin(cell.theta_rad);
    for (int p = 0; p < pair_count(); ++p) {
      const double a = lag_per_direction_[static_cast<size_t>(p)].dot(shape_.axis);
      const PairSpectra::Value v = spectra_.At(p, a * c);
      out.value += v.r;
      out.gradient(0) += v.dr * (-a * s);
      out.hessian(0, 0) += v.d2r * a * a * s * s + v.dr * (-a * c);
    }
    out.hessian(1, 1) = -1.0;  // unused direction: keeps the matrix definite
    return out;
  }
  const bool planar = shape_.shape == ArrayShape::kPlanar;
  const Vec3 normal = planar ? shape_.axis : cell.u;
  const Vec3 other = std::abs(normal.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  out.basis.col(0) = normal.cross(other).normalized();
  out.basis.col(1) = normal.cross(out.basis.col(0));
  double radial = 0.0;  // the sphere's curvature: u(v) = (u + E v) / |u + E v|
  for (int p = 0; p < pair_count(); ++p) {
    const Vec3& d = lag_per_direction_[static_cast<size_t>(p)];
    const PairSpectra::Value v = spectra_.At(p, d.dot(cell.u));
    const Eigen::Vector2d a = out.basis.transpose() * d;
    out.value += v.r;
    out.gradient += v.dr * a;
    out.hessian += v.d2r * a * a.transpose();
    radial += v.dr * d.dot(cell.u);
  }
  if (!planar) out.hessian -= radial * Eigen::Matrix2d::Identity();
  return out;
}

SrpPhat::Cell SrpPhat::Moved(const Cell& cell, const Probe& probe, const Eigen::Vector2d& step) const {
  Cell next = cell;
  if (linear()) {
    next.theta_rad = std::clamp(cell.theta_rad + step(0), 0.0, std::numbers::pi);
  } else if (shape_.shape == ArrayShape::kPlanar) {
    const Vec3& n = shape_.axis;
    Vec3 w = cell.u - cell.u.dot(n) * n + probe.basis * step;
    if (w.norm() > 1.0) w.normalize();
    next.u = w + std::sqrt(std::max(0.0, 1.0 - w.squaredNorm())) * n;
  } else {
    next.u = (cell.u + probe.basis * step).normalized();
  }
  return next;
}

SrpPhat::Cell SrpPhat::Refine(Cell cell, double* statistic) const {
  const double max_step = 2.0 * leaf_radius_rad_;
  Probe probe = ProbeAt(cell);
  for (int iteration = 0; iteration < kRefineIterations; ++iteration) {
    Eigen::Vector2d step;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(probe.hessian);
    if (eig.eigenvalues().maxCoeff() < 0.0) {
      step = -probe.hessian.ldlt().solve(probe.gradient);
    } else {
      const double g = probe.gradient.norm();
      step = g > 0.0 ? Eigen::Vector2d(0.25 * max_step * probe.gradient / g) : Eigen::Vector2d::Zero();
    }
    if (step.norm() > max_step) step *= max_step / step.norm();
    bool improved = false;
    for (int h = 0; h < kHalvings && !improved; ++h, step *= 0.5) {
      const Cell next = Moved(cell, probe, step);
      const Probe there = ProbeAt(next);
      if (there.value > probe.value) {
        cell = next;
        probe = there;
        improved = true;
      }
    }
    if (!improved || step.norm() < kConverged_rad) break;
  }
  // Exact(cell): the probe's value is the same sum over pairs of the same R_p.
  *statistic = probe.value / spectra_.noise_sigma() / std::sqrt(static_cast<double>(pair_count()));
  return cell;
}

DirectionPeak SrpPhat::Describe(const Cell& cell, double statistic, bool statistic_is_whole) const {
  DirectionPeak peak;
  peak.statistic = statistic;
  peak.previous_statistic = Whole(cell, true);
  peak.rise = (statistic_is_whole ? statistic : Whole(cell, false)) - peak.previous_statistic;
  peak.threshold = threshold_;
  peak.power_db = 20.0 * std::log10(std::max(statistic, 1e-9) / std::sqrt(static_cast<double>(pair_count())));
  if (linear()) {
    peak.cone_angle_rad = cell.theta_rad;
    return peak;
  }
  Vec3 u = cell.u;
  if (shape_.shape == ArrayShape::kPlanar) {
    const PlanarDirection resolved = ResolvePlanarMirror(u, shape_.axis, options_.source_side);
    u = resolved.direction;
    peak.mirror_ambiguous = resolved.mirror_ambiguous;
    peak.mirror_direction = resolved.mirror_direction;
  }
  peak.direction = u;
  peak.azimuth_rad = AzimuthRad(u);
  peak.elevation_rad = ElevationRad(u);
  return peak;
}

SrpPhat::Cell SrpPhat::RefineOtherStarts(Cell best, double* statistic) {
  ends_.assign(1, best);
  for (const Cell& start : starts_) {  // in decreasing bound
    // No point of this cell (nor of the later ones) can beat the statistic: its bound, on
    // the sampled field, times the margin the continuous GCC can exceed its samples by.
    if (start.bound * interpolation_margin_ <= *statistic) break;
    // The largest bounds crowd about a peak: a start beside an end point already reached
    // would climb to it again.
    if (std::any_of(ends_.begin(), ends_.end(), [&](const Cell& end) { return Apart(start, end) < kSameStartRad; }))
      continue;
    double other = 0.0;
    const Cell refined = Refine(start, &other);
    ends_.push_back(refined);
    if (other > *statistic) {
      *statistic = other;
      best = refined;
    }
  }
  return best;
}

StatusOr<std::vector<DirectionPeak>> SrpPhat::Analyse(const float* frame) {
  LOCALIZER_RETURN_IF_ERROR(spectra_.Analyse(frame, &field_input_));
  if (options_.keep_whole_field) whole_field_ = field_input_;  // same sizes every frame: allocates once
  std::vector<DirectionPeak> peaks;
  struct Found {
    Cell cell;
    size_t slot = 0;  // removed_[slot]: per pair and bin, what RemoveDelay took
    double statistic = 0.0;
    bool whole = false;  // statistic is Whole(cell, false): found with nothing removed, not re-refined
  };
  std::vector<Found> found;
  auto remove = [&](Found* f) {
    if (removed_.size() <= f->slot) removed_.resize(f->slot + 1);
    std::vector<std::vector<std::complex<double>>>& taken = removed_[f->slot];
    taken.resize(static_cast<size_t>(pair_count()));
    for (int p = 0; p < pair_count(); ++p) spectra_.RemoveDelay(p, Lag(p, f->cell), &taken[static_cast<size_t>(p)]);
  };
  while (static_cast<int>(found.size()) < options_.max_sources) {
    if (!found.empty()) spectra_.FillFields(&field_input_);  // the residual, for the search
    field_.Build(field_input_);
    if (!found.empty() && FieldCeiling() < threshold_) break;  // nothing left can reach it
    Cell best;
    if (!Search(&best)) break;
    double statistic = 0.0;
    best = Refine(best, &statistic);
    if (!starts_.empty()) best = RefineOtherStarts(best, &statistic);
    if (!(statistic >= threshold_)) break;
    if (!found.empty() && statistic < options_.min_relative_statistic * found.front().statistic) break;
    found.push_back({best, found.size(), statistic, found.empty()});
    if (static_cast<int>(found.size()) == options_.max_sources) break;
    remove(&found.back());
    // Each earlier source was refined with this one in its spectrum, which biased it: put it
    // back, refine it among the others' residual, and take it out again (kReestimations
    // passes). A removal at a biased lag leaves structured residue the next search finds.
    for (int pass = 0; pass < kReestimations && found.size() > 1; ++pass) {
      for (Found& f : found) {
        for (int p = 0; p < pair_count(); ++p)
          spectra_.RestoreDelay(p, Lag(p, f.cell), removed_[f.slot][static_cast<size_t>(p)]);
        f.cell = Refine(f.cell, &f.statistic);
        f.whole = false;
        remove(&f);
      }
    }
  }
  // A later source's re-estimation among the others can leave its statistic below the
  // threshold (it had taken up a biased earlier source's residue): no longer a detection.
  std::erase_if(found, [this](const Found& f) { return !(f.statistic >= threshold_); });
  std::stable_sort(found.begin(), found.end(),
                   [](const Found& a, const Found& b) { return a.statistic > b.statistic; });
  for (const Found& f : found) peaks.push_back(Describe(f.cell, f.statistic, f.whole));
  return peaks;
}

double SrpPhat::Statistic(const Vec3& direction) const {
  Cell cell;
  if (linear()) {
    cell.theta_rad = ConeAngleRad(direction.normalized(), shape_.axis);
  } else {
    cell.u = direction.normalized();
  }
  return Exact(cell);
}

}  // namespace localizer::engine
