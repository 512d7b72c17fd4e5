#include "engine/acquisition/acquisition.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "engine/acquisition/presence.h"
#include "engine/array/multilateration.h"

namespace localizer::engine {
namespace {

Vec3 UnitFromCell(double mu, double phi) {
  const double s = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  return Vec3(s * std::cos(phi), s * std::sin(phi), mu);
}

// Distance from p to the box (0 inside); infinite sides allowed.
double DistanceToBox(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  Vec3 d;
  for (int i = 0; i < 3; ++i) d(i) = std::max({lo(i) - p(i), 0.0, p(i) - hi(i)});
  return d.norm();
}

}  // namespace

Status AcquisitionOptions::Validate() const {
  if (!(false_alarm > 0.0) || false_alarm > 0.1) return InvalidArgument("false_alarm must be in (0, 0.1]");
  if (max_modes < 1 || max_modes > 16) return InvalidArgument("max_modes must be in [1, 16]");
  if (!(mode_margin >= 0.0) || mode_margin > 100.0) return InvalidArgument("mode_margin must be in [0, 100]");
  if (azimuth_cells < 4 || azimuth_cells > 1024 || polar_cells < 2 || polar_cells > 512 || range_cells < 2 ||
      range_cells > 256) {
    return InvalidArgument("acquisition grid must have 4..1024 azimuth, 2..512 polar and 2..256 range cells");
  }
  if (refinement_budget < 1 || refinement_budget > 4096)
    return InvalidArgument("refinement_budget must be in [1, 4096]");
  if (!(search_radius_m >= 0.0) || search_radius_m > 1e7) return InvalidArgument("search_radius_m must be in [0, 1e7]");
  for (int i = 0; i < 3; ++i) {
    if (std::isnan(bounds_min_m(i)) || std::isnan(bounds_max_m(i)) || !(bounds_min_m(i) < bounds_max_m(i))) {
      return InvalidArgument("bounds must have min < max on every axis");
    }
  }
  return Status::Ok();
}

StatusOr<Acquisition> Acquisition::Create(const ArrayGeometry& array, const AcquisitionOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  return Acquisition(array, options);
}

Acquisition::Acquisition(const ArrayGeometry& array, const AcquisitionOptions& options)
    : array_(array), options_(options) {
  const double dphi = 2.0 * M_PI / options.azimuth_cells;
  const double dmu = 2.0 / options.polar_cells;
  for (int i = 0; i < options.polar_cells; ++i) {
    const double mu0 = -1.0 + i * dmu, mu1 = mu0 + dmu;
    for (int j = 0; j < options.azimuth_cells; ++j) {
      const double phi0 = j * dphi, phi1 = phi0 + dphi;
      Direction d;
      d.unit = UnitFromCell(0.5 * (mu0 + mu1), 0.5 * (phi0 + phi1));
      double radius = 0.0;
      for (double mu : {mu0, 0.5 * (mu0 + mu1), mu1}) {
        for (double phi : {phi0, 0.5 * (phi0 + phi1), phi1}) {
          radius = std::max(radius, std::acos(std::clamp(d.unit.dot(UnitFromCell(mu, phi)), -1.0, 1.0)));
        }
      }
      d.angular_radius_rad = radius;
      d.chord_per_range = 2.0 * std::sin(0.5 * radius);
      directions_.push_back(d);
    }
  }
}

double Acquisition::search_radius_m() const {
  return options_.search_radius_m > 0.0 ? options_.search_radius_m : 10.0 * array_.aperture_m();
}

bool Acquisition::InBounds(const Vec3& p) const {
  return (p.array() >= options_.bounds_min_m.array()).all() && (p.array() <= options_.bounds_max_m.array()).all();
}

double Acquisition::CrossLag(int q, const Eigen::VectorXd& pair_lags) const {
  return pair_lags(array_.pair_of_sensor(field_.cross_sensor_b(q))) -
         pair_lags(array_.pair_of_sensor(field_.cross_sensor_a(q)));
}

Eigen::RowVector3d Acquisition::CrossGradient(int q, const Eigen::MatrixXd& pair_jacobian) const {
  return pair_jacobian.row(array_.pair_of_sensor(field_.cross_sensor_b(q))) -
         pair_jacobian.row(array_.pair_of_sensor(field_.cross_sensor_a(q)));
}

double Acquisition::Score(const Vec3& p) const {
  const double scale = field_.sample_rate_hz();
  const Eigen::VectorXd lags = array_.Tdoa(p) * scale;
  const int pairs = field_.reference_pairs();
  double s = 0.0;
  for (int q = 0; q < pairs; ++q) s += field_.At(q, lags(q));
  for (int q = pairs; q < field_.pair_count(); ++q) s += field_.At(q, CrossLag(q, lags));
  return s;
}

AcquisitionResult Acquisition::Search(const Measurement& m) {
  AcquisitionResult out;
  field_.Build(m);
  measurement_ = &m;
  struct Forget {  // the measurement is only borrowed for this call
    const Measurement** slot;
    ~Forget() { *slot = nullptr; }
  } forget{&measurement_};
  const int pairs = field_.reference_pairs();
  const int all_pairs = field_.pair_count();
  const int usable = field_.usable_pairs();
  out.presence.threshold = std::numeric_limits<double>::infinity();
  if (field_.usable_reference_pairs() < 3 || pairs != array_.pair_count()) return out;
  const double fs = m.sample_rate_hz;
  const double c = array_.sound_speed_mps();
  const Vec3 centre = array_.centroid_m();
  const double radius = search_radius_m();
  const double r_min = std::min(0.05 * array_.aperture_m(), 0.5 * radius);
  const int shells = options_.range_cells;
  const double q = std::pow(radius / r_min, 1.0 / (shells - 1));

  struct Cell {
    float upper;
    int direction;
    int shell;
  };
  std::vector<Cell> cells;
  cells.reserve(directions_.size() * static_cast<size_t>(shells));
  // Per field pair (reference, then cross): the cell centre's lag and the cell's half-width.
  std::vector<double> lags(static_cast<size_t>(all_pairs)), widths(static_cast<size_t>(all_pairs));
  std::vector<double> sensor_range(static_cast<size_t>(array_.sensor_count()));
  std::vector<Vec3> sensor_unit(static_cast<size_t>(array_.sensor_count()));
  // Shell s > 0 spans [r_min q^(s-1), r_min q^s].
  std::vector<double> shell_lo(static_cast<size_t>(shells), 0.0);
  for (int s = 1; s < shells; ++s) shell_lo[static_cast<size_t>(s)] = r_min * std::pow(q, s - 1);
  // The cell's centre and circumradius.
  auto geometry = [&](int d, int s, Vec3* x, double* rad) {
    if (s == 0) {  // the ball about the centre
      *x = centre;
      *rad = r_min;
      return;
    }
    const double r_lo = shell_lo[static_cast<size_t>(s)], r_hi = r_lo * q;
    const Direction& dir = directions_[static_cast<size_t>(d)];
    *x = centre + 0.5 * (r_lo + r_hi) * dir.unit;
    const double chord = r_hi * dir.chord_per_range;
    const double half_depth = 0.5 * (r_hi - r_lo);
    *rad = std::sqrt(chord * chord + half_depth * half_depth);
  };
  const int ref = array_.reference_sensor();
  auto lag_windows = [&](const Vec3& x, double rad) {
    for (int k = 0; k < array_.sensor_count(); ++k) {
      const Vec3 to_k = x - array_.sensor_m(k);
      const double d_k = to_k.norm();
      sensor_range[static_cast<size_t>(k)] = d_k;
      sensor_unit[static_cast<size_t>(k)] = d_k > 0.0 ? Vec3(to_k / d_k) : Vec3::Zero();
    }
    // Pair (a, b): lag (d_b - d_a) fs / c; |grad lag| <= 2 fs / c near a sensor, where the
    // unit vectors are undefined.
    auto window = [&](int p, int a, int b) {
      const double d_a = sensor_range[static_cast<size_t>(a)], d_b = sensor_range[static_cast<size_t>(b)];
      lags[static_cast<size_t>(p)] = (d_b - d_a) / c * fs;
      const double grad =
          (d_b > rad && d_a > rad)
              ? (sensor_unit[static_cast<size_t>(b)] - sensor_unit[static_cast<size_t>(a)]).norm() / c * fs
              : 2.0 * fs / c;
      widths[static_cast<size_t>(p)] = grad * rad + 0.5;
    };
    for (int p = 0; p < pairs; ++p) window(p, ref, array_.sensor_of_pair(p));
    for (int p = pairs; p < all_pairs; ++p) window(p, field_.cross_sensor_a(p), field_.cross_sensor_b(p));
  };
  for (int s = 0; s < shells; ++s) {
    const int dirs = s == 0 ? 1 : static_cast<int>(directions_.size());
    for (int d = 0; d < dirs; ++d) {
      Vec3 x;
      double rad = 0.0;
      geometry(d, s, &x, &rad);
      if (DistanceToBox(x, options_.bounds_min_m, options_.bounds_max_m) > rad) continue;
      lag_windows(x, rad);
      double upper = 0.0;
      for (int p = 0; p < all_pairs; ++p)
        upper += field_.MaxAround(p, lags[static_cast<size_t>(p)], widths[static_cast<size_t>(p)]);
      cells.push_back({static_cast<float>(upper), d, s});
    }
  }
  const size_t keep = std::min(cells.size(), static_cast<size_t>(options_.refinement_budget) * 4);
  std::partial_sort(cells.begin(), cells.begin() + static_cast<std::ptrdiff_t>(keep), cells.end(),
                    [](const Cell& a, const Cell& b) { return a.upper > b.upper; });

  const double margin = options_.mode_margin * std::sqrt(static_cast<double>(usable));
  // A search direction's radius: the cap of an equal-area cell's solid angle, 4 pi / N = pi r^2.
  const double cos_cell = std::cos(2.0 / std::sqrt(static_cast<double>(options_.azimuth_cells * options_.polar_cells)));
  std::vector<PositionMode> modes;
  double best = -std::numeric_limits<double>::infinity();
  int refined = 0;
  std::vector<double> lo(static_cast<size_t>(all_pairs)), hi(static_cast<size_t>(all_pairs));
  // Refines from `start`; keeps a new mode (or the stronger of two that coincide). With
  // `siblings`, the closed form's other exact solutions of a new mode's lags are refined too
  // (a 4-sensor array's second solution lies where no cell order guarantees a visit).
  std::function<void(const Vec3&, const std::vector<double>&, const std::vector<double>&, bool, bool)> consider =
      [&](const Vec3& start, const std::vector<double>& a, const std::vector<double>& b, bool siblings, bool earlier) {
        PositionMode mode;
        if (!Refine(start, a, b, &mode)) return;
        mode.earlier_arrival = earlier;
        // A solution beyond the searched sphere says "far, that way": it stands on the sphere
        // (scored there), its range spread below reaching back over the volume.
        const double reach_m = (mode.position_m - centre).norm();
        const bool parked = reach_m > 1.5 * radius;
        if (parked) {
          // Across the bearing the spread is angular, so it shrinks with the range it is parked
          // at (a least-squares solve over redundant pairs can slide out to millions of metres,
          // where the same angles span kilometres); along it, the whole sphere.
          const Vec3 out_unit = (mode.position_m - centre) / reach_m;
          const Mat3 across = Mat3::Identity() - out_unit * out_unit.transpose();
          const double shrink = radius / reach_m;
          mode.covariance_m2 = shrink * shrink * across * mode.covariance_m2 * across +
                               radius * radius * out_unit * out_unit.transpose();
          mode.position_m = centre + radius * out_unit;
          mode.score = Score(mode.position_m);
        }
        if (!InBounds(mode.position_m)) return;
        // The source lies within the searched sphere: no axis of the covariance may exceed it
        // (far away, range is barely observable and (H^T W H)^-1 grows without bound).
        const Eigen::SelfAdjointEigenSolver<Mat3> eig(mode.covariance_m2);
        mode.covariance_m2 = eig.eigenvectors() *
                             eig.eigenvalues().cwiseMax(0.0).cwiseMin(radius * radius).asDiagonal() *
                             eig.eigenvectors().transpose();
        // The same mode when each lies within 3 sd of the other by the other's own covariance:
        // a sum of the two would let a far mode's range spread (tens of metres) swallow a
        // distinct near one, e.g. a 4-sensor array's second exact solution near the array.
        const Mat3 floor = std::pow(1e-6 * array_.aperture_m(), 2) * Mat3::Identity();
        auto within = [&](const Vec3& delta, const Mat3& covariance) {
          return delta.dot((covariance + floor).ldlt().solve(delta)) < 9.0;
        };
        // Two far solutions parked on the sphere within one search direction's radius are one
        // hypothesis ("far, that way"), however the solves that found them differed in range.
        auto both_parked_alike = [&](const PositionMode& other) {
          const Vec3 other_out = other.position_m - centre;
          return parked && std::abs(other_out.norm() - radius) <= 1e-9 * radius &&
                 other_out.normalized().dot((mode.position_m - centre).normalized()) >= cos_cell;
        };
        for (PositionMode& other : modes) {
          const Vec3 delta = mode.position_m - other.position_m;
          if ((within(delta, mode.covariance_m2) && within(delta, other.covariance_m2)) || both_parked_alike(other) ||
              delta.norm() < 1e-3 * array_.aperture_m()) {
            const bool kept = other.earlier_arrival || earlier;
            if (mode.score > other.score) other = mode;
            other.earlier_arrival = kept;
            best = std::max(best, mode.score);
            return;
          }
        }
        modes.push_back(mode);
        best = std::max(best, mode.score);
        if (!siblings) return;
        const Vec3 found = mode.position_m;
        for (const Vec3& candidate : ClosedFormCandidates(array_, array_.Tdoa(found))) {
          if ((candidate - found).norm() < 1e-3 * array_.aperture_m()) continue;
          const Eigen::VectorXd lag = array_.Tdoa(candidate) * fs;
          std::vector<double> c_lo(static_cast<size_t>(all_pairs)), c_hi(static_cast<size_t>(all_pairs));
          for (int p = 0; p < all_pairs; ++p) {
            const double at = p < pairs ? lag(p) : CrossLag(p, lag);
            c_lo[static_cast<size_t>(p)] = at - 3.0;
            c_hi[static_cast<size_t>(p)] = at + 3.0;
          }
          consider(candidate, c_lo, c_hi, /*siblings=*/false, earlier);
        }
      };
  for (size_t i = 0; i < keep && refined < options_.refinement_budget; ++i) {
    if (cells[i].upper < best - margin) break;  // no cell left can hold a mode near the best
    Vec3 x;
    double rad = 0.0;
    geometry(cells[i].direction, cells[i].shell, &x, &rad);
    // A cell holding a mode already found would most likely refine onto it again: the budget
    // goes to cells elsewhere (a 4-sensor array's other solution has the same lags, so only
    // the starting point tells the two apart).
    bool holds_mode = false;
    for (const PositionMode& mode : modes) holds_mode |= (mode.position_m - x).norm() <= rad;
    if (holds_mode) continue;
    lag_windows(x, rad);
    for (int p = 0; p < all_pairs; ++p) {
      lo[static_cast<size_t>(p)] = lags[static_cast<size_t>(p)] - widths[static_cast<size_t>(p)];
      hi[static_cast<size_t>(p)] = lags[static_cast<size_t>(p)] + widths[static_cast<size_t>(p)];
    }
    ++refined;
    consider(x, lo, hi, /*siblings=*/true, /*earlier=*/false);
  }
  // One channel's earlier arrival (acquisition.h): the direct path where that channel's
  // strongest arrival was an echo. Its modes survive whatever their score.
  if (options_.earlier_arrivals) {
    const std::vector<PositionMode> found = modes;
    for (const PositionMode& mode : found) {
      std::vector<double> shifted;
      if (mode.score < best - margin || !EarlierArrival(mode.position_m, &shifted)) continue;
      Eigen::VectorXd tdoa_s(pairs);
      for (int p = 0; p < pairs; ++p) tdoa_s(p) = shifted[static_cast<size_t>(p)] / fs;
      std::vector<double> a(static_cast<size_t>(all_pairs)), b(static_cast<size_t>(all_pairs));
      for (int p = 0; p < all_pairs; ++p) {
        const double at = p < pairs ? shifted[static_cast<size_t>(p)] : CrossLag(p, tdoa_s * fs);
        a[static_cast<size_t>(p)] = at - 2.0;
        b[static_cast<size_t>(p)] = at + 2.0;
      }
      std::vector<Vec3> starts = ClosedFormCandidates(array_, tdoa_s);
      if (starts.empty()) starts.push_back(mode.position_m);
      for (const Vec3& start : starts) {
        if (start.allFinite()) consider(start, a, b, /*siblings=*/true, /*earlier=*/true);
      }
    }
  }
  std::sort(modes.begin(), modes.end(), [](const PositionMode& a, const PositionMode& b) { return a.score > b.score; });
  for (const PositionMode& mode : modes) {
    if (static_cast<int>(out.modes.size()) >= options_.max_modes) break;
    if (mode.score >= best - margin || mode.earlier_arrival) out.modes.push_back(mode);
  }
  // The search chose among at most M lag combinations (3 degrees of freedom).
  double product = 1.0, widest = 1.0;
  for (int p = 0; p < pairs; ++p) {
    if (!field_.usable(p)) continue;
    const double w = field_.last_lag(p) - field_.first_lag(p) + 1;
    product *= w;
    widest = std::max(widest, w);
  }
  const double combinations = std::min(product, 8.0 * widest * widest * widest);
  out.presence.threshold = PresenceThreshold(options_.false_alarm, combinations);
  if (out.modes.empty()) {
    // No position could be solved: report the bound no position can exceed (each pair's
    // largest value anywhere in its window), so a frame says how far from present it was.
    double unconstrained = 0.0, lag = 0.0, value = 0.0;
    for (int p = 0; p < all_pairs; ++p) {
      if (field_.usable(p) && field_.ArgMax(p, field_.first_lag(p), field_.last_lag(p), &lag, &value)) {
        unconstrained += value;
      }
    }
    out.presence.statistic = unconstrained / std::sqrt(static_cast<double>(usable));
  } else {
    out.presence.statistic = out.modes.front().score / std::sqrt(static_cast<double>(usable));
  }
  out.presence.present = !out.modes.empty() && out.presence.statistic >= out.presence.threshold;
  return out;
}

PresenceResult Acquisition::Around(const Measurement& m, const Vec3& position_m, const Mat3& covariance_m2) {
  PresenceResult out;
  field_.Build(m, /*with_levels=*/false);
  const int usable = field_.usable_pairs();
  out.threshold = std::numeric_limits<double>::infinity();
  if (usable == 0 || field_.reference_pairs() != array_.pair_count()) return out;
  const double fs = m.sample_rate_hz;
  const Eigen::VectorXd pair_lag = array_.Tdoa(position_m) * fs;
  const Eigen::MatrixXd jac = array_.TdoaJacobian(position_m) * fs;
  const int pairs = field_.reference_pairs();
  double sum = 0.0, combinations = 1.0, unconstrained = 0.0;
  for (int p = 0; p < field_.pair_count(); ++p) {
    if (!field_.usable(p)) continue;
    // A cross pair (a, b) reads lag_b - lag_a, with the gradient's difference.
    Eigen::Vector3d row;
    double lag_p = 0.0;
    if (p < pairs) {
      row = jac.row(p).transpose();
      lag_p = pair_lag(p);
    } else {
      row = CrossGradient(p, jac).transpose();
      lag_p = CrossLag(p, pair_lag);
    }
    const double spread = std::sqrt(std::max(0.0, row.dot(covariance_m2 * row)));
    const double half = std::min(3.0 * spread + 1.0, static_cast<double>(field_.last_lag(p) - field_.first_lag(p)));
    const double a = std::max(lag_p - half, static_cast<double>(field_.first_lag(p)));
    const double b = std::min(lag_p + half, static_cast<double>(field_.last_lag(p)));
    double at = 0.0, value = 0.0;
    if (a <= b && field_.ArgMax(p, a, b, &at, &value)) {
      sum += value;
      combinations *= std::max(1.0, std::floor(b) - std::ceil(a) + 1.0);
    }
    if (field_.ArgMax(p, field_.first_lag(p), field_.last_lag(p), &at, &value)) unconstrained += value;
  }
  out.statistic = sum / std::sqrt(static_cast<double>(usable));
  out.unconstrained = unconstrained / std::sqrt(static_cast<double>(usable));
  out.threshold = PresenceThreshold(options_.false_alarm, combinations);
  out.present = out.statistic >= out.threshold;
  return out;
}

}  // namespace localizer::engine
