#include "engine/doa/near_field.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "engine/core/far_field.h"

namespace localizer::engine {
namespace {

constexpr int kRaySteps = 32;           // ranges probed along each direction
constexpr double kDegree_rad = std::numbers::pi / 180.0;
constexpr int kLinearWindowSteps = 15;  // cone angles within 30 degrees of the track's,
constexpr double kLinearStep_rad = 2.0 * kDegree_rad;  // 2 degrees apart
constexpr int kPlanarWindowSteps = 5;  // directions within 15 degrees on two axes,
constexpr double kPlanarStep_rad = 3.0 * kDegree_rad;  // 3 degrees apart
constexpr int kIterations = 8;         // Gauss-Newton steps per start
constexpr double kMaxStepLag = 0.5;    // samples of lag a step may move any pair
constexpr double kDefaultMinRange = 0.1;   // apertures
constexpr double kDefaultMaxRange = 50.0;  // apertures
constexpr double kPlaneAngle = 1e-3;       // rad: the axis within the source plane
constexpr double kPlaneOffset = 0.01;      // apertures: the centroid on the plane (or 1 mm)

}  // namespace

StatusOr<NearFieldLocator> NearFieldLocator::Create(const std::vector<Vec3>& sensors_m,
                                                    const NearFieldOptions& options) {
  auto shape = ClassifyArray(sensors_m);
  if (!shape.ok()) return shape.status();
  if (!(options.sample_rate_hz > 0.0) || !(options.sound_speed_mps > 0.0)) {
    return InvalidArgument("near-field positions need a positive sample rate and sound speed");
  }
  if (!options.source_side.allFinite() || !options.plane_normal.allFinite()) {
    return InvalidArgument("source_side and source_plane must be finite");
  }
  if (!(options.min_range_m >= 0.0) || !(options.max_range_m >= 0.0) ||
      (options.max_range_m > 0.0 && options.max_range_m <= options.min_range_m)) {
    return InvalidArgument("near-field ranges must satisfy 0 <= min_range_m < max_range_m");
  }
  NearFieldLocator out;
  out.shape_ = *shape;
  out.options_ = options;
  out.sensors_m_ = sensors_m;
  const Vec3& c = shape->centroid_m;
  switch (shape->shape) {
    case ArrayShape::kVolumetric:
      // Every direction and range is observable; a stated side only narrows the search.
      out.side_ = options.source_side.norm() > 0.0 ? Vec3(options.source_side.normalized()) : Vec3::Zero();
      out.free_ = 3;
      out.basis_ = Eigen::Matrix3d::Identity();
      break;
    case ArrayShape::kPlanar: {
      if (options.source_side.norm() == 0.0) {
        return InvalidArgument("a planar array needs source_side for position (the side of its plane the sources are on)");
      }
      const Vec3 side = options.source_side.normalized();
      if (std::abs(side.dot(shape->axis)) < 1e-6) {
        return InvalidArgument("source_side lies in the planar array's plane, so it cannot tell a position from its "
                               "mirror image");
      }
      out.side_ = side;
      out.free_ = 3;
      out.basis_ = Eigen::Matrix3d::Identity();
      break;
    }
    case ArrayShape::kLinear: {
      if (options.plane_normal.norm() == 0.0 || !options.plane_point_m.allFinite()) {
        return InvalidArgument("a linear array needs source_plane for position (a plane that holds the array and "
                               "the sources)");
      }
      if (options.source_side.norm() == 0.0) {
        return InvalidArgument("a linear array needs source_side for position (which side of the array, in "
                               "source_plane, the sources are on)");
      }
      const Vec3 n = options.plane_normal.normalized();
      if (std::abs(n.dot(shape->axis)) > kPlaneAngle) {
        return InvalidArgument("source_plane does not hold the linear array: its axis is " +
                               std::to_string(std::asin(std::min(1.0, std::abs(n.dot(shape->axis)))) * 180.0 /
                                              3.141592653589793) +
                               " degrees out of the plane");
      }
      const double offset_m = std::abs((c - options.plane_point_m).dot(n));
      if (offset_m > std::max(1e-3, kPlaneOffset * shape->aperture_m)) {
        return InvalidArgument("source_plane does not hold the linear array: its centroid is " +
                               std::to_string(offset_m) + " m from the plane");
      }
      // The side within the plane, across the axis.
      Vec3 across = options.source_side - options.source_side.dot(n) * n;
      across -= across.dot(shape->axis) * shape->axis;
      if (across.norm() < 1e-6 * options.source_side.norm()) {
        return InvalidArgument("source_side has no part in source_plane across the linear array's axis, so it cannot "
                               "tell the two sides apart");
      }
      out.side_ = across.normalized();
      out.free_ = 2;
      out.basis_.col(0) = shape->axis;
      out.basis_.col(1) = out.side_;
      out.basis_.col(2) = n;
      break;
    }
  }
  out.min_range_m_ = options.min_range_m > 0.0 ? options.min_range_m : kDefaultMinRange * shape->aperture_m;
  out.max_range_m_ = options.max_range_m > 0.0 ? options.max_range_m : kDefaultMaxRange * shape->aperture_m;
  if (out.max_range_m_ <= out.min_range_m_) out.max_range_m_ = 2.0 * out.min_range_m_;
  return out;
}

Vec3 NearFieldLocator::DirectionAt(double cone_angle_rad) const {
  return std::cos(cone_angle_rad) * shape_.axis + std::sin(cone_angle_rad) * side_;
}

Vec3 NearFieldLocator::PositionOf(const Eigen::Vector3d& x) const {
  Eigen::Vector3d free = x;
  if (free_ == 2) free(2) = 0.0;
  return shape_.centroid_m + basis_ * free;
}

Eigen::Vector3d NearFieldLocator::CoordinatesOf(const Vec3& position_m) const {
  Eigen::Vector3d x = basis_.transpose() * (position_m - shape_.centroid_m);  // basis_ is orthonormal
  if (free_ == 2) x(2) = 0.0;
  return x;
}

void NearFieldLocator::Pin(Eigen::Matrix3d* m, double diagonal) const {
  if (free_ == 3) return;
  m->row(2).setZero();
  m->col(2).setZero();
  (*m)(2, 2) = diagonal;
}

bool NearFieldLocator::OnSide(const Vec3& position_m) const {
  return !sided() || (position_m - shape_.centroid_m).dot(side_) > 0.0;
}

double NearFieldLocator::Lag(int i, int j, const Vec3& position_m, Vec3* gradient) const {
  const Vec3 to_i = position_m - sensors_m_[static_cast<size_t>(i)];
  const Vec3 to_j = position_m - sensors_m_[static_cast<size_t>(j)];
  const double di = to_i.norm(), dj = to_j.norm();
  const double per_m = options_.sample_rate_hz / options_.sound_speed_mps;
  if (gradient != nullptr) {
    *gradient = per_m * ((di > 0.0 ? Vec3(to_i / di) : Vec3::Zero()) - (dj > 0.0 ? Vec3(to_j / dj) : Vec3::Zero()));
  }
  return (di - dj) * per_m;
}

double NearFieldLocator::PairLag(const PairSpectra& spectra, int p, const Vec3& position_m) const {
  const auto [i, j] = spectra.sensors_of(p);
  return Lag(i, j, position_m, nullptr);
}

NearFieldLocator::Probe NearFieldLocator::ProbeAt(const PairSpectra& spectra, const Vec3& position_m,
                                                  Spectrum read) const {
  Probe out;
  out.position_m = position_m;
  out.pairs.reserve(static_cast<size_t>(spectra.pair_count()));
  for (int p = 0; p < spectra.pair_count(); ++p) {
    const auto [i, j] = spectra.sensors_of(p);
    Vec3 gradient_m;
    const double lag = Lag(i, j, position_m, &gradient_m);
    const PairSpectra::Value v = read == Spectrum::kWhole ? spectra.WholeValueAt(p, lag) : spectra.At(p, lag);
    const Eigen::Vector3d g = basis_.transpose() * gradient_m;
    out.value += v.r;
    out.gradient += v.dr * g;
    out.hessian += v.d2r * g * g.transpose();
    out.pairs.push_back({g, v.r, v.d2r});
  }
  return out;
}

NearFieldFix NearFieldLocator::Bound(const PairSpectra& spectra, const Probe& fit) const {
  NearFieldFix fix;
  fix.fitted_m = fit.position_m;
  const Vec3 line_m = fit.position_m - shape_.centroid_m;
  fix.range_m = line_m.norm();
  const double noise_var = spectra.noise_sigma() * spectra.noise_sigma();
  Eigen::Matrix3d fisher = Eigen::Matrix3d::Zero();
  int used = 0;
  for (const PairTerm& pair : fit.pairs) {
    if (!(pair.r > 0.0) || !(pair.d2r < 0.0)) continue;
    fisher += pair.lag_gradient * pair.lag_gradient.transpose() * (pair.r * -pair.d2r / noise_var);
    ++used;
  }
  if (used < free_ || !(fix.range_m > 0.0)) return fix;
  Pin(&fisher, 1.0);
  // A plane wave carries no range information: the Fisher matrix is then singular along the
  // line of sight up to rounding, and whether LDLT calls it positive turned on the last bits
  // of the spectrum's sums. A prior worth 1e-12 of its trace keeps the solve defined, so such a
  // frame reports a huge range sd (far field) rather than NaN.
  fisher.diagonal().array() += 1e-12 * fisher.trace();
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(fisher);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return fix;
  Eigen::Matrix3d covariance_free = ldlt.solve(Eigen::Matrix3d::Identity());
  if (free_ == 2) covariance_free(2, 2) = 0.0;  // the plane's normal: fixed
  const Mat3 covariance_m2 = basis_ * covariance_free * basis_.transpose();
  const Vec3 u = line_m / fix.range_m;
  const double sd_m = std::sqrt(std::max(0.0, u.dot(covariance_m2 * u)));
  if (!std::isfinite(sd_m)) return fix;
  fix.range_sd_m = sd_m;
  const bool inside = fix.range_m > min_range_m_ && fix.range_m < max_range_m_;
  if (inside && sd_m <= kFarFieldRangeShare * fix.range_m) {
    fix.near_field = true;
    fix.position_m = fit.position_m;
    fix.covariance_m2 = covariance_m2;
  }
  return fix;
}

double NearFieldLocator::CoarseSpectrum(const PairSpectra& spectra, const Measurement& field,
                                        const Vec3& position_m) const {
  double sum = 0.0;
  for (int p = 0; p < spectra.pair_count(); ++p) {
    const auto [i, j] = spectra.sensors_of(p);
    const std::vector<float>& gcc = field.pairs[static_cast<size_t>(p)].gcc;
    const double at = Lag(i, j, position_m, nullptr) + 0.5 * static_cast<double>(gcc.size() - 1);
    if (!(at >= 0.0) || at > static_cast<double>(gcc.size() - 1)) continue;
    const auto k = std::min(static_cast<size_t>(at), gcc.size() - 2);
    const double f = at - static_cast<double>(k);
    sum += (1.0 - f) * gcc[k] + f * gcc[k + 1];
  }
  return sum;
}

std::vector<Vec3> NearFieldLocator::CandidateDirections(const Vec3& u) const {
  std::vector<Vec3> out{u};
  if (free_ == 2) {
    const double theta = ConeAngleRad(u, shape_.axis);
    for (int k = -kLinearWindowSteps; k <= kLinearWindowSteps; ++k) {
      const double t = theta + k * kLinearStep_rad;
      if (k != 0 && t > 0.0 && t < std::numbers::pi) out.push_back(DirectionAt(t));
    }
    return out;
  }
  const Vec3 other = std::abs(u.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 e1 = u.cross(other).normalized(), e2 = u.cross(e1);
  for (int a = -kPlanarWindowSteps; a <= kPlanarWindowSteps; ++a) {
    for (int b = -kPlanarWindowSteps; b <= kPlanarWindowSteps; ++b) {
      if (a == 0 && b == 0) continue;
      const Vec3 v = (u + kPlanarStep_rad * (a * e1 + b * e2)).normalized();
      if (!sided() || v.dot(side_) > 0.0) out.push_back(v);
    }
  }
  return out;
}

NearFieldFix NearFieldLocator::Locate(const PairSpectra& spectra, const Measurement& field, const Vec3& direction,
                                      Spectrum read) const {
  Vec3 u = direction;
  if (free_ == 2) u = u - u.dot(basis_.col(2)) * basis_.col(2);  // into the plane
  if (!(u.norm() > 0.0) || !u.allFinite() || field.pairs.size() != static_cast<size_t>(spectra.pair_count())) {
    return NearFieldFix{};
  }
  u.normalize();
  if (sided() && u.dot(side_) <= 0.0) u = (u + (1e-3 - u.dot(side_)) * side_).normalized();

  // 1. The coarse grid: ranges along each direction of the window, from the sampled field.
  // Starts: the best point on the direction itself and the best anywhere in the window.
  const double ratio = std::pow(max_range_m_ / min_range_m_, 1.0 / (kRaySteps - 1));
  const std::vector<Vec3> directions = CandidateDirections(u);
  Vec3 starts_m[2];
  double best_coarse[2] = {-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (size_t d = 0; d < directions.size(); ++d) {
    double range_m = min_range_m_;
    for (int k = 0; k < kRaySteps; ++k, range_m *= ratio) {
      const Vec3 p_m = shape_.centroid_m + range_m * directions[d];
      const double value = CoarseSpectrum(spectra, field, p_m);
      for (int s = d == 0 ? 0 : 1; s < 2; ++s) {
        if (value > best_coarse[s]) {
          best_coarse[s] = value;
          starts_m[s] = p_m;
        }
      }
    }
  }

  // 2. Gauss-Newton from each start on the exact spectrum; each probe's pair terms serve the
  // next step, and the best end point's the bound.
  Probe best;
  best.value = -std::numeric_limits<double>::infinity();
  const int starts = (starts_m[0] - starts_m[1]).norm() > 1e-9 ? 2 : 1;  // the window's best may be on u
  for (int k = 0; k < starts; ++k) {
    Probe here = ProbeAt(spectra, starts_m[k], read);
    for (int iteration = 0; iteration < kIterations; ++iteration) {
      Eigen::Matrix3d hessian = here.hessian;
      Eigen::Vector3d gradient = here.gradient;
      Pin(&hessian, -1.0);
      if (free_ == 2) gradient(2) = 0.0;
      // Ascent: -H^-1 g where H is negative definite; otherwise a gradient step.
      Eigen::Vector3d step = -hessian.ldlt().solve(gradient);
      if (!step.allFinite() || step.dot(gradient) <= 0.0) step = gradient;
      double largest_lag_rate = 0.0;  // samples of lag the step moves the worst pair
      for (const PairTerm& pair : here.pairs) {
        largest_lag_rate = std::max(largest_lag_rate, std::abs(pair.lag_gradient.dot(step)));
      }
      if (largest_lag_rate > kMaxStepLag) step *= kMaxStepLag / largest_lag_rate;
      // Backtrack until S does not fall and the position stays on the side.
      bool moved = false;
      for (int halving = 0; halving < 6 && !moved; ++halving, step *= 0.5) {
        const Vec3 next_m = PositionOf(CoordinatesOf(here.position_m) + step);
        if (!OnSide(next_m)) continue;
        Probe there = ProbeAt(spectra, next_m, read);
        if (there.value >= here.value) {
          here = std::move(there);
          moved = true;
        }
      }
      if (!moved || largest_lag_rate < 1e-3) break;
    }
    if (here.value > best.value) best = std::move(here);
  }
  return Bound(spectra, best);
}

}  // namespace localizer::engine
