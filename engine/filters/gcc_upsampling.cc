#include "engine/filters/gcc_upsampling.h"

#include <cmath>
#include <numbers>

namespace localizer::engine {
namespace {

double Kernel(double x) {
  if (x == 0.0) return 1.0;
  if (std::abs(x) >= kGccUpsampleTaps) return 0.0;
  const double px = std::numbers::pi * x;
  return std::sin(px) / px * (0.5 + 0.5 * std::cos(px / kGccUpsampleTaps));
}

}  // namespace

void UpsampleGcc(const std::vector<float>& gcc, int factor, std::vector<float>* out) {
  const int size = static_cast<int>(gcc.size());
  if (size == 0) {
    out->clear();
    return;
  }
  out->resize(static_cast<size_t>((size - 1) * factor + 1));
  // The kernel weights depend only on the phase j % factor: compute them once per phase.
  thread_local std::vector<double> weights;
  weights.resize(static_cast<size_t>(factor * 2 * kGccUpsampleTaps));
  for (int phase = 0; phase < factor; ++phase) {
    for (int t = 0; t < 2 * kGccUpsampleTaps; ++t) {
      const double x = static_cast<double>(phase) / factor - (t - kGccUpsampleTaps + 1);
      weights[static_cast<size_t>(phase * 2 * kGccUpsampleTaps + t)] = Kernel(x);
    }
  }
  for (int j = 0; j < static_cast<int>(out->size()); ++j) {
    const int base = j / factor, phase = j % factor;
    double sum = 0.0;
    for (int t = 0; t < 2 * kGccUpsampleTaps; ++t) {
      const int m = base + t - kGccUpsampleTaps + 1;
      if (m < 0 || m >= size) continue;
      sum += weights[static_cast<size_t>(phase * 2 * kGccUpsampleTaps + t)] * gcc[static_cast<size_t>(m)];
    }
    (*out)[static_cast<size_t>(j)] = static_cast<float>(sum);
  }
}

}  // namespace localizer::engine
