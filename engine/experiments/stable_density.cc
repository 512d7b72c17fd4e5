#include "engine/experiments/stable_density.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <string>
#include <utility>

#include "engine/sim/invalid_value.h"

namespace localizer::engine::experiments {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kHalfPi = 0.5 * kPi;
constexpr double kTableHalfWidth = 60.0;  // u in [-60, 60]
constexpr double kTableStep = 0.02;
constexpr double kLogFloor = -700.0;
constexpr double kRelativeTolerance = 1e-10;
constexpr int kRoughPanels = 32;
constexpr int kMaxDepth = 40;
constexpr double kNearZero = 1e-6;

// The integral in phi = pi/2 - th, phi in (0, pi/2 + theta0), where every factor is a sine
// that vanishes at an end, computed without cancellation there:
//     cos th = sin phi,   sin(a (theta0 + th)) = sin(d + a phi),
//     cos(a theta0 + (a-1) th) = sin(d + (a-1) phi),   d = pi - a (theta0 + pi/2) >= 0
// (d = 0 for b = -1, where V stays finite at th = pi/2: the short tail). Then
//     ln g(phi) = (a/(a-1)) ln x + ln cos(a theta0) / (a-1)
//                 + (a/(a-1)) (ln sin phi - ln sin(d + a phi)) + ln sin(d + (a-1) phi) - ln sin
//                 phi,
// increasing from -inf (or a finite value when d = 0) to +inf.
struct Zolotarev {
  double alpha;
  double theta0;
  double d;
  double log_x_term;

  Zolotarev(double x, double a, double b) : alpha(a), theta0(std::atan(b * std::tan(kHalfPi * a)) / a) {
    d = std::max(kPi - a * (theta0 + kHalfPi), 0.0);  // rounding can make it -1e-16
    log_x_term = a / (a - 1.0) * std::log(x) + std::log(std::cos(a * theta0)) / (a - 1.0);
  }
  double upper() const { return kHalfPi + theta0; }
  double LogG(double phi) const {
    const double a = alpha;
    const double log_sin = std::log(std::sin(phi));
    return log_x_term + a / (a - 1.0) * (log_sin - std::log(std::sin(d + a * phi))) +
           std::log(std::sin(d + (a - 1.0) * phi)) - log_sin;
  }
  double Integrand(double phi) const {
    const double log_g = LogG(phi);
    if (!(log_g < 700.0)) return 0.0;  // g e^-g underflows (also at the singular ends)
    return std::exp(log_g - std::exp(log_g));
  }
};

struct SimpsonPanel {
  double a, b, fa, fm, fb, whole;
};

// Adaptive Simpson to an absolute tolerance, halved at each split (so the panels' errors
// add up to at most `tolerance`).
template <typename F>
double AdaptiveSimpson(const F& f, const SimpsonPanel& p, double tolerance, int depth) {
  const double m = 0.5 * (p.a + p.b);
  const double flm = f(0.5 * (p.a + m));
  const double frm = f(0.5 * (m + p.b));
  const double left = (m - p.a) / 6.0 * (p.fa + 4.0 * flm + p.fm);
  const double right = (p.b - m) / 6.0 * (p.fm + 4.0 * frm + p.fb);
  const double delta = left + right - p.whole;
  if (depth >= kMaxDepth || (depth >= 2 && std::abs(delta) <= 15.0 * tolerance)) {
    return left + right + delta / 15.0;
  }
  return AdaptiveSimpson(f, {p.a, m, p.fa, flm, p.fm, left}, 0.5 * tolerance, depth + 1) +
         AdaptiveSimpson(f, {m, p.b, p.fm, frm, p.fb, right}, 0.5 * tolerance, depth + 1);
}

// Composite Simpson with `panels` panels: a first estimate that sets the tolerance.
template <typename F>
double CompositeSimpson(const F& f, double a, double b, int panels) {
  const double h = (b - a) / panels;
  double sum = f(a) + f(b);
  for (int i = 1; i < 2 * panels; ++i) sum += (i % 2 == 1 ? 4.0 : 2.0) * f(a + 0.5 * h * i);
  return sum * h / 6.0;
}

template <typename F>
double Integrate(const F& f, double a, double b, double tolerance) {
  if (!(b > a)) return 0.0;
  const double fa = f(a), fb = f(b), fm = f(0.5 * (a + b));
  return AdaptiveSimpson(f, {a, b, fa, fm, fb, (b - a) / 6.0 * (fa + 4.0 * fm + fb)}, tolerance, 0);
}

// f(x) for x > 0.
double PositiveSideDensity(double x, double alpha, double beta) {
  const Zolotarev z(x, alpha, beta);
  const auto integrand = [&z](double th) { return z.Integrand(th); };
  // The top of the bump, g = 1 (at the lower end when g > 1 throughout).
  double lo = 0.0, hi = z.upper();
  for (int i = 0; i < 200 && hi - lo > 1e-15; ++i) {
    const double mid = 0.5 * (lo + hi);
    (z.LogG(mid) > 0.0 ? hi : lo) = mid;
  }
  const double top = 0.5 * (lo + hi);
  // Each side falls monotonically from its value at the top; a coarse pass sizes the
  // tolerance.
  const double rough =
      CompositeSimpson(integrand, 0.0, top, kRoughPanels) + CompositeSimpson(integrand, top, z.upper(), kRoughPanels);
  const double tolerance = 0.5 * kRelativeTolerance * rough;
  const double integral = Integrate(integrand, 0.0, top, tolerance) + Integrate(integrand, top, z.upper(), tolerance);
  return alpha / (kPi * (alpha - 1.0) * x) * integral;
}

}  // namespace

double StableStandardDensity(double x, double alpha, double beta) {
  // Within 1e-6 of 0 the bump squeezes against the end of the range and the quadrature
  // loses digits (1e-9: 3e-5 relative); f(0) is then within 1e-6 relative of f(x).
  if (x > kNearZero) return PositiveSideDensity(x, alpha, beta);
  if (x < -kNearZero) return PositiveSideDensity(-x, alpha, -beta);
  const double zeta = -beta * std::tan(kHalfPi * alpha);
  const double theta0 = std::atan(-zeta) / alpha;
  return std::tgamma(1.0 + 1.0 / alpha) * std::cos(theta0) / (kPi * std::pow(1.0 + zeta * zeta, 0.5 / alpha));
}

namespace {

// ln f of S1(alpha, beta, 1, 0) on the grid.
std::vector<double> BuildStandardTable(double alpha, double beta) {
  const int half = static_cast<int>(std::lround(kTableHalfWidth / kTableStep));
  std::vector<double> log_f(2 * half + 1);
  for (int i = -half; i <= half; ++i) {
    const double f = StableStandardDensity(i * kTableStep, alpha, beta);
    log_f[i + half] = f > 0.0 ? std::max(std::log(f), kLogFloor) : kLogFloor;
  }
  return log_f;
}

std::shared_ptr<const std::vector<double>> CachedStandardTable(double alpha, double beta) {
  static std::mutex mutex;
  // Never destroyed, so no exit-time ordering problem.
  static auto* cache = new std::map<std::pair<double, double>, std::shared_ptr<const std::vector<double>>>;
  const std::lock_guard<std::mutex> lock(mutex);
  auto& entry = (*cache)[{alpha, beta}];
  if (entry == nullptr) entry = std::make_shared<const std::vector<double>>(BuildStandardTable(alpha, beta));
  return entry;
}

}  // namespace

StatusOr<StableDensityTable> StableDensityTable::Create(const AlphaStable& params) {
  LOCALIZER_RETURN_IF_ERROR(params.Validate());
  if (!(params.alpha > 1.0)) {
    return sim_detail::Invalid("alpha", params.alpha, "the stable density table needs 1 < alpha <= 2");
  }
  StableDensityTable table(params);
  table.log_scale_ = std::log(params.scale);
  if (params.alpha == 2.0) return table;  // Gaussian: closed form
  table.log_f_ = CachedStandardTable(params.alpha, params.beta);
  // A power-law tail where that side has mass (the right one for beta > -1).
  constexpr double kMassless = 1e-9;
  if (1.0 + params.beta > kMassless) table.right_tail_power_ = 1.0 + params.alpha;
  if (1.0 - params.beta > kMassless) table.left_tail_power_ = 1.0 + params.alpha;
  return table;
}

double StableDensityTable::StandardLogDensity(double u) const {
  if (params_.alpha == 2.0) return -0.25 * u * u - 0.5 * std::log(4.0 * kPi);  // N(0, 2)
  const std::vector<double>& log_f = *log_f_;
  const double last = static_cast<double>(log_f.size() - 1);
  const double position = (u + kTableHalfWidth) / kTableStep;
  if (position >= last) {
    const double edge = log_f.back();
    return std::max(edge - right_tail_power_ * std::log(u / kTableHalfWidth), kLogFloor);
  }
  if (position <= 0.0) {
    const double edge = log_f.front();
    return std::max(edge - left_tail_power_ * std::log(-u / kTableHalfWidth), kLogFloor);
  }
  const auto i = static_cast<size_t>(position);
  const double t = position - static_cast<double>(i);
  return log_f[i] + t * (log_f[i + 1] - log_f[i]);
}

double StableDensityTable::LogDensity(double x) const {
  const double u = (x - params_.location) / params_.scale;
  if (!std::isfinite(u)) return kLogFloor - log_scale_;
  return StandardLogDensity(u) - log_scale_;
}

}  // namespace localizer::engine::experiments
