#include "engine/sim/fractional_delay.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "engine/sim/kaiser_window.h"

namespace localizer::engine {
namespace {

constexpr int kHalf = FractionalDelayInterpolator::kTaps / 2;

double WindowedSinc(double u) {
  // Exact zeros at the integers (sin(pi k) is only ~1e-16 in floating point), so integer
  // positions reproduce the samples exactly.
  if (u == std::round(u)) return u == 0.0 ? 1.0 : 0.0;
  const double window = KaiserWindow(u / kHalf, FractionalDelayInterpolator::kKaiserBeta);
  const double pi_u = std::numbers::pi * u;
  return std::sin(pi_u) / pi_u * window;
}

// The same sum with samples outside [0, size) taken as zero.
double EvaluateNearEdge(const double* samples, int64_t size, int64_t first, const double* row0, const double* row1,
                        double blend) {
  double value = 0.0;
  for (int j = 0; j < FractionalDelayInterpolator::kTaps; ++j) {
    const int64_t i = first + j;
    if (i < 0 || i >= size) continue;
    value += ((1.0 - blend) * row0[j] + blend * row1[j]) * samples[i];
  }
  return value;
}

}  // namespace

FractionalDelayInterpolator::FractionalDelayInterpolator() : table_(static_cast<size_t>(kPhases + 1) * kTaps) {
  for (int p = 0; p <= kPhases; ++p) {
    const double fraction = static_cast<double>(p) / kPhases;
    for (int j = 0; j < kTaps; ++j) {
      table_[static_cast<size_t>(p) * kTaps + j] = WindowedSinc(fraction + kHalf - 1 - j);
    }
  }
}

double FractionalDelayInterpolator::Evaluate(const double* samples, int64_t size, double position) const {
  const double floor_position = std::floor(position);
  // Phase index and the blend towards the next phase. A fraction that rounds up to 1.0 (x just
  // below an integer) lands on the last interval with blend 1, which is the same kernel.
  const double phase = (position - floor_position) * kPhases;
  const int p = std::min(static_cast<int>(phase), kPhases - 1);
  const double blend = phase - p;
  const double* row0 = &table_[static_cast<size_t>(p) * kTaps];
  const double* row1 = row0 + kTaps;
  const int64_t first = static_cast<int64_t>(floor_position) - (kHalf - 1);
  if (first < 0 || first + kTaps > size) {
    return EvaluateNearEdge(samples, size, first, row0, row1, blend);
  }
  // Fixed-size Eigen maps: the two 32-term dot products unroll into SIMD packets.
  using Taps = Eigen::Matrix<double, kTaps, 1>;
  const Eigen::Map<const Taps> x(samples + first);
  const Eigen::Map<const Taps> h0(row0);
  const Eigen::Map<const Taps> h1(row1);
  return (1.0 - blend) * h0.dot(x) + blend * h1.dot(x);
}

}  // namespace localizer::engine
