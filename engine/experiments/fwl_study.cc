#include "engine/experiments/fwl_study.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/experiments/experiment_random.h"
#include "engine/tws/steady_state_gain.h"

namespace localizer::engine::experiments {
namespace {

// Integers m of the Q-format value m 2^-b; products are exact in int64 for b <= 24 and
// coefficients below 2^7.
struct QFormat {
  int bits;
  int64_t one;  // 2^b

  int64_t Quantise(double v) const { return static_cast<int64_t>(std::floor(v * static_cast<double>(one) + 0.5)); }
  // round(c m 2^-b): add half an LSB, arithmetic shift right (floor).
  int64_t Multiply(int64_t c, int64_t m) const { return (c * m + (one >> 1)) >> bits; }
  int64_t Saturate(int64_t m, int64_t* overflows) const {
    if (m >= one) {
      ++*overflows;
      return one - 1;
    }
    if (m < -one) {
      ++*overflows;
      return -one;
    }
    return m;
  }
};

}  // namespace

StatusOr<FwlSystem> FwlSystemPreset(int system) {
  FwlSystem s;
  if (system == 1) {
    s.name = "1: normalised alpha-beta, no scaling";
    s.units = "full scale";
    s.period_s = 1.0;
    s.measurement_sigma = 0.05;
    s.accel_sigma = 0.02 * 0.05;  // lambda = 0.02
    s.scale = {1.0, 1.0};
    s.start_position = 0.4;
    s.velocity = -0.02;
    return s;
  }
  if (system == 2) {
    s.name = "2: seed's constant-velocity target, scaled";
    s.units = "km";
    s.period_s = 60.0 / 33.0;
    s.measurement_sigma = 0.01;
    s.accel_sigma = 0.05e-3;
    s.scale = {2.0, 1.0 / 32.0};
    s.start_position = 1.0;
    s.velocity = -0.01;
    return s;
  }
  return InvalidArgument("system is " + std::to_string(system) + ", must be 1 or 2");
}

Status FwlOptions::Validate() const {
  if (system != 1 && system != 2) return InvalidArgument("system is " + std::to_string(system) + ", must be 1 or 2");
  if (runs < 1 || runs > 1000000) return InvalidArgument("runs is " + std::to_string(runs) + ", must be in 1..1000000");
  if (min_bits < 4 || max_bits > 24 || min_bits > max_bits)
    return InvalidArgument("bits " + std::to_string(min_bits) + ".." + std::to_string(max_bits) +
                           " must lie within 4..24, min <= max");
  if (first_step < 1 || last_step < first_step || last_step > 10000)
    return InvalidArgument("steps " + std::to_string(first_step) + ".." + std::to_string(last_step) +
                           " must satisfy 1 <= first <= last <= 10000");
  return Status::Ok();
}

Eigen::Matrix2d RoundOffCovariance(const Eigen::Matrix2d& phi, const Eigen::Vector2d& counts, int bits) {
  const double q = std::ldexp(1.0, -2 * bits) / 12.0;
  const Eigen::Matrix2d noise = q * counts.asDiagonal().toDenseMatrix();
  Eigen::Matrix2d sum = Eigen::Matrix2d::Zero();
  Eigen::Matrix2d power = Eigen::Matrix2d::Identity();
  for (int j = 0; j < 100000; ++j) {
    const Eigen::Matrix2d term = power * noise * power.transpose();
    sum += term;
    if (term.cwiseAbs().maxCoeff() < 1e-15 * sum.cwiseAbs().maxCoeff()) break;
    power = phi * power;
  }
  return sum;
}

StatusOr<FwlResult> RunFwlStudy(const FwlOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  StatusOr<FwlSystem> preset = FwlSystemPreset(options.system);
  if (!preset.ok()) return preset.status();
  FwlResult result;
  result.system = *preset;
  const FwlSystem& sys = result.system;
  const double t = sys.period_s;
  const tws::AlphaBeta ab = tws::KalataAlphaBeta(sys.accel_sigma, sys.measurement_sigma, t);
  result.alpha = ab.alpha;
  result.beta = ab.beta;
  Eigen::Matrix2d f;
  f << 1.0, t, 0.0, 1.0;
  const Eigen::Vector2d k(ab.alpha, ab.beta / t);
  Eigen::Matrix2d phi = f;
  phi.row(0) -= k(0) * f.row(0);
  phi.row(1) -= k(1) * f.row(0);
  const Eigen::Matrix2d s = sys.scale.asDiagonal();
  const Eigen::Matrix2d s_inv = sys.scale.cwiseInverse().asDiagonal();
  const Eigen::Matrix2d phi_s = s_inv * phi * s;
  const Eigen::Vector2d k_s = s_inv * k * sys.scale(0);

  for (int bits = options.min_bits; bits <= options.max_bits; ++bits) {
    const QFormat qf{bits, int64_t{1} << bits};
    int64_t c[2][2], g[2];
    Eigen::Matrix2d phi_q;
    Eigen::Vector2d k_q, counts = Eigen::Vector2d::Zero();
    for (int i = 0; i < 2; ++i) {
      for (int j = 0; j < 2; ++j) {
        c[i][j] = qf.Quantise(phi_s(i, j));
        phi_q(i, j) = std::ldexp(static_cast<double>(c[i][j]), -bits);
        if (c[i][j] % qf.one != 0) counts(i) += 1.0;  // an integer coefficient is exact
      }
      g[i] = qf.Quantise(k_s(i));
      k_q(i) = std::ldexp(static_cast<double>(g[i]), -bits);
      if (g[i] % qf.one != 0) counts(i) += 1.0;
    }
    FwlRow row;
    row.bits = bits;
    double sum = 0.0;
    int64_t n = 0;
    for (int run = 0; run < options.runs; ++run) {
      // Runs share nothing: the noise of run r is keyed by (seed, r) only, the same at
      // every word length (common random numbers make the table's trend smooth).
      std::mt19937_64 engine = ExperimentEngine(options.seed, ExperimentStream::kMeasurementNoise, run);
      auto measure = [&](int step) {
        const double truth = sys.start_position + sys.velocity * t * step;
        const double z = truth + sys.measurement_sigma * StandardNormal(engine);
        return qf.Saturate(qf.Quantise(z / sys.scale(0)), &row.overflows);
      };
      const int64_t z0 = measure(0);
      int64_t m[2] = {z0, 0};
      Eigen::Vector2d x(std::ldexp(static_cast<double>(z0), -bits), 0.0);
      for (int step = 1; step <= options.last_step; ++step) {
        const int64_t mz = measure(step);
        const double zq = std::ldexp(static_cast<double>(mz), -bits);
        int64_t next[2];
        for (int i = 0; i < 2; ++i) {
          const int64_t acc = qf.Multiply(c[i][0], m[0]) + qf.Multiply(c[i][1], m[1]) + qf.Multiply(g[i], mz);
          next[i] = qf.Saturate(acc, &row.overflows);
        }
        m[0] = next[0];
        m[1] = next[1];
        x = (phi_q * x + k_q * zq).eval();
        if (step >= options.first_step) {
          const double e = (std::ldexp(static_cast<double>(m[0]), -bits) - x(0)) * sys.scale(0);
          sum += e * e;
          ++n;
        }
      }
    }
    row.simulated = sum / static_cast<double>(n);
    row.computed_scaled = sys.scale(0) * sys.scale(0) * RoundOffCovariance(phi_q, counts, bits)(0, 0);
    const Eigen::Matrix2d phi_unscaled = s * phi_q * s_inv;
    row.computed_unscaled = RoundOffCovariance(phi_unscaled, counts, bits)(0, 0);
    result.rows.push_back(row);
  }
  return result;
}

std::vector<SeedFwlFigure> SeedFwlFigures(int system) {
  if (system == 1) return {{16, 8.52e-9, 6.42e-9}, {6, 6.90e-3, 6.73e-3}};
  if (system == 2) return {{16, 1.18e-6, 1.26e-7}, {10, 3.93e-1, 5.25e-3}};
  return {};
}

}  // namespace localizer::engine::experiments
