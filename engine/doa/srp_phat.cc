#include "engine/doa/srp_phat.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "engine/acquisition/presence.h"

namespace localizer::engine {
namespace {
constexpr int kMinRoots = 16;
// At most this many roots: an array whose leaves number more is searched by branch and
// bound from this lattice; one with fewer has leaves for roots (a plain grid, no bounds).
constexpr int kMaxRoots = 8192;
// Covering radius of the Fibonacci lattice, with a margin: 1.5 x the radius of a cap of the
// lattice's area per point (2 / sqrt(N)); tests/doa checks the search against brute force.
constexpr double kRootCoverage = 1.5;
constexpr double kSplitMargin = 1.1;  // the tangent plane's distortion over a cell

bool Finite(double v) { return std::isfinite(v); }
}  // namespace

Status SrpOptions::Validate() const {
  if (!(sample_rate_hz > 0.0) || !Finite(sample_rate_hz)) return InvalidArgument("sample_rate_hz must be positive");
  if (!(sound_speed_mps > 0.0) || !Finite(sound_speed_mps)) return InvalidArgument("sound_speed_mps must be positive");
  if (frame_samples < 16 || frame_samples > (1 << 20)) return InvalidArgument("frame_samples must be in [16, 2^20]");
  if (max_sources < 1 || max_sources > 16) return InvalidArgument("max_sources must be in [1, 16]");
  if (!(false_alarm > 0.0) || false_alarm > 0.1) return InvalidArgument("false_alarm must be in (0, 0.1]");
  if (!source_side.allFinite()) return InvalidArgument("source_side must be finite");
  if (hop_samples < 0 || (hop_samples > 0 && (frame_samples + hop_samples - 1) / hop_samples > 64))
    return InvalidArgument("hop_samples must be 0 or in [frame_samples / 64, ...)");
  if (cell_budget < 64 || cell_budget > (1 << 20)) return InvalidArgument("cell_budget must be in [64, 2^20]");
  if (search_starts < 1 || search_starts > 64) return InvalidArgument("search_starts must be in [1, 64]");
  if (!(min_relative_statistic >= 0.0) || !(min_relative_statistic < 1.0))
    return InvalidArgument("min_relative_statistic must be in [0, 1)");
  return Status::Ok();
}

SrpPhat::SrpPhat(const ArrayShapeInfo& shape, const SrpOptions& options, PairSpectra spectra)
    : shape_(shape), options_(options), spectra_(std::move(spectra)) {}

StatusOr<SrpPhat> SrpPhat::Create(const std::vector<Vec3>& sensors_m, const SrpOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  StatusOr<ArrayShapeInfo> shape = ClassifyArray(sensors_m);
  if (!shape.ok()) return shape.status();
  if (shape->shape == ArrayShape::kPlanar && options.source_side.norm() > 0.0 &&
      std::abs(options.source_side.normalized().dot(shape->axis)) < 1e-6) {
    return InvalidArgument("source_side lies in the array's plane, so it cannot tell a direction from its mirror");
  }
  const double per_m = options.sample_rate_hz / options.sound_speed_mps;
  const Vec3 axis = shape->axis;
  std::vector<Vec3> d;
  std::vector<double> distance_m;  // per pair: its sensors' distance (the diffuse weighting's)
  double spread = 0.0;
  const bool linear = shape->shape == ArrayShape::kLinear;
  for (size_t i = 0; i < sensors_m.size(); ++i) {
    for (size_t j = i + 1; j < sensors_m.size(); ++j) {
      d.emplace_back(-(sensors_m[i] - sensors_m[j]) * per_m);
      distance_m.push_back((sensors_m[i] - sensors_m[j]).norm());
      spread = std::max(spread, linear ? std::abs(d.back().dot(axis)) : d.back().norm());
    }
  }
  PairSpectraOptions po;
  po.sensors = static_cast<int>(sensors_m.size());
  po.frame_samples = options.frame_samples;
  po.sample_rate_hz = options.sample_rate_hz;
  po.band_low_hz = options.band_low_hz;
  po.band_high_hz = options.band_high_hz;
  po.max_lag_samples = static_cast<int>(std::ceil(spread)) + 2;  // + the bound's half sample and interpolation
  // The last frame that does not overlap this one: a source that starts within this frame
  // or the one before it is absent there.
  po.rise_lag_frames =
      options.hop_samples > 0 ? (options.frame_samples + options.hop_samples - 1) / options.hop_samples : 1;
  if (options.diffuse_weighting) {
    po.sound_speed_mps = options.sound_speed_mps;
    po.diffuse_distance_m = std::move(distance_m);
  }
  po.signal_weighting = options.signal_weighting;
  StatusOr<PairSpectra> spectra = PairSpectra::Create(po);
  if (!spectra.ok()) return spectra.status();

  SrpPhat srp(*shape, options, std::move(*spectra));
  srp.lag_per_direction_ = std::move(d);
  srp.max_spread_ = spread;
  srp.leaf_radius_rad_ = 0.5 / spread;
  const double r = srp.leaf_radius_rad_;
  double leaves = 4.0 / (r * r);                                    // the sphere: 4 pi / (pi r^2)
  if (shape->shape == ArrayShape::kPlanar) leaves = 2.0 / (r * r);  // a hemisphere
  if (linear) leaves = std::numbers::pi / (2.0 * r);                // arcs of 2 r over [0, pi]
  srp.threshold_ = PresenceThreshold(options.false_alarm, std::max(1.0, leaves));
  // A band [f1, f2] (cycles per sample) peak read half a sample off keeps its mean cos:
  // (sin(pi f2) - sin(pi f1)) / (pi (f2 - f1)); the margin is its inverse, 10 % more.
  const double f1 = options.band_low_hz / options.sample_rate_hz;
  const double f2 = options.band_high_hz > 0.0 ? options.band_high_hz / options.sample_rate_hz : 0.5;
  const double kept =
      f2 > f1 ? (std::sin(std::numbers::pi * f2) - std::sin(std::numbers::pi * f1)) / (std::numbers::pi * (f2 - f1))
              : 1.0;
  srp.interpolation_margin_ = 1.1 / std::max(kept, 0.1);
  // Roots as fine as the leaves when that is at most kMaxRoots of them.
  if (linear) {
    srp.root_count_ = std::clamp(static_cast<int>(std::ceil(std::numbers::pi / (2.0 * r))), kMinRoots, kMaxRoots);
    srp.root_radius_rad_ = 0.5 * std::numbers::pi / srp.root_count_;
  } else {
    const double needed = std::pow(kRootCoverage * 2.0 / r, 2.0);
    srp.root_count_ = static_cast<int>(std::clamp(std::ceil(needed), 8.0 * kMinRoots, static_cast<double>(kMaxRoots)));
    srp.root_radius_rad_ = kRootCoverage * 2.0 / std::sqrt(static_cast<double>(srp.root_count_));
  }
  srp.roots_ = srp.Roots();
  if (!srp.roots_.empty() && srp.Leaf(srp.roots_.front())) {
    // LagField::At's reading of each root's lags, for a window of lags -max_lag..max_lag.
    const int window = 2 * po.max_lag_samples + 1;
    for (int p = 0; p < srp.pair_count(); ++p) {
      for (const Cell& c : srp.roots_) {
        const double x = srp.Lag(p, c) + po.max_lag_samples;
        int i0 = 0;
        double w0 = 0.0, w1 = 0.0;  // outside the window: 0
        if (x >= 0.0 && x <= static_cast<double>(window - 1)) {
          const auto i = static_cast<int>(x);
          if (i + 1 >= window) {
            i0 = window - 1;
            w0 = 1.0;
          } else {
            const double f = x - static_cast<double>(i);
            i0 = i;
            w0 = 1.0 - f;
            w1 = f;
          }
        }
        srp.grid_index_.push_back(i0);
        srp.grid_w0_.push_back(w0);
        srp.grid_w1_.push_back(w1);
      }
    }
  }
  return srp;
}

double SrpPhat::Lag(int p, const Cell& cell) const {
  const Vec3& d = lag_per_direction_[static_cast<size_t>(p)];
  return linear() ? d.dot(shape_.axis) * std::cos(cell.theta_rad) : d.dot(cell.u);
}

double SrpPhat::Spread(int p, double radius_rad) const {
  const Vec3& d = lag_per_direction_[static_cast<size_t>(p)];
  return (linear() ? std::abs(d.dot(shape_.axis)) : d.norm()) * radius_rad;
}

double SrpPhat::Bound(const Cell& cell) const {
  double sum = 0.0;
  for (int p = 0; p < pair_count(); ++p) sum += field_.MaxAround(p, Lag(p, cell), Spread(p, cell.radius_rad) + 0.5);
  return sum / std::sqrt(static_cast<double>(pair_count()));
}

double SrpPhat::Centre(const Cell& cell) const {
  double sum = 0.0;
  for (int p = 0; p < pair_count(); ++p) sum += field_.At(p, Lag(p, cell));
  return sum / std::sqrt(static_cast<double>(pair_count()));
}

bool SrpPhat::GridCentres() {
  if (grid_index_.empty()) return false;
  const size_t roots = roots_.size(), pairs = static_cast<size_t>(pair_count());
  grid_sums_.assign(roots, 0.0);
  for (size_t p = 0; p < pairs; ++p) {
    const std::vector<float>& values = field_.values(static_cast<int>(p));
    grid_samples_.assign(values.begin(), values.end());
    grid_samples_.push_back(0.0);  // w1 = 0 reads it at the window's last sample
    const double* __restrict g = grid_samples_.data();
    const int* __restrict index = grid_index_.data() + p * roots;
    const double* __restrict w0 = grid_w0_.data() + p * roots;
    const double* __restrict w1 = grid_w1_.data() + p * roots;
    double* __restrict sum = grid_sums_.data();
    for (size_t r = 0; r < roots; ++r) sum[r] += w0[r] * g[index[r]] + w1[r] * g[index[r] + 1];
  }
  return true;
}

bool SrpPhat::Leaf(const Cell& cell) const { return max_spread_ * cell.radius_rad <= 0.5 + 1e-9; }

std::vector<SrpPhat::Cell> SrpPhat::Roots() const {
  std::vector<Cell> roots;
  if (linear()) {
    for (int i = 0; i < root_count_; ++i) {
      Cell c;
      c.theta_rad = (2 * i + 1) * root_radius_rad_;
      c.radius_rad = root_radius_rad_;
      roots.push_back(c);
    }
    return roots;
  }
  const double radius = root_radius_rad_;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < root_count_; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / root_count_;
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    Cell c;
    c.u = Vec3(rho * std::cos(golden * i), rho * std::sin(golden * i), z);
    c.radius_rad = radius;
    // Planar arrays: only cells that reach the normal's hemisphere.
    if (shape_.shape == ArrayShape::kPlanar && c.u.dot(shape_.axis) < -std::sin(radius)) continue;
    roots.push_back(c);
  }
  return roots;
}

void SrpPhat::Split(const Cell& cell, std::vector<Cell>* children) const {
  children->clear();
  if (linear()) {
    for (double side : {-0.5, 0.5}) {
      Cell c;
      c.theta_rad = std::clamp(cell.theta_rad + side * cell.radius_rad, 0.0, std::numbers::pi);
      c.radius_rad = 0.5 * cell.radius_rad;
      children->push_back(c);
    }
    return;
  }
  const Vec3 other = std::abs(cell.u.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 e1 = cell.u.cross(other).normalized(), e2 = cell.u.cross(e1);
  const double half = 0.5 * cell.radius_rad;
  for (double a : {-half, half}) {
    for (double b : {-half, half}) {
      Cell c;
      c.u = (cell.u + a * e1 + b * e2).normalized();
      c.radius_rad = kSplitMargin * cell.radius_rad / std::numbers::sqrt2;
      if (shape_.shape == ArrayShape::kPlanar && c.u.dot(shape_.axis) < -std::sin(c.radius_rad)) continue;
      children->push_back(c);
    }
  }
}

}  // namespace localizer::engine
