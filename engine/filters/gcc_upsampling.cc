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
  constexpr int kSpan = 2 * kGccUpsampleTaps;
  out->resize(static_cast<size_t>(size - 1) * static_cast<size_t>(factor) + 1);
  // Kernel weights depend only on the phase j % factor; the input is zero padded by
  // kGccUpsampleTaps on both sides so the inner loop has no bounds checks.
  thread_local std::vector<float> weights, padded;
  thread_local int weights_factor = 0;
  if (weights_factor != factor) {  // the kernel table depends only on the factor
    weights_factor = factor;
    weights.resize(static_cast<size_t>(factor) * kSpan);
    for (int phase = 0; phase < factor; ++phase) {
      for (int t = 0; t < kSpan; ++t) {
        const double x = static_cast<double>(phase) / factor - (t - kGccUpsampleTaps + 1);
        weights[static_cast<size_t>(phase) * kSpan + static_cast<size_t>(t)] = static_cast<float>(Kernel(x));
      }
    }
  }
  padded.assign(static_cast<size_t>(size) + 2 * static_cast<size_t>(kGccUpsampleTaps), 0.0f);
  std::copy(gcc.begin(), gcc.end(), padded.begin() + kGccUpsampleTaps);
  // One phase at a time, as a short convolution vectorised across output positions, then
  // interleaved into the fine grid.
  thread_local std::vector<float> phase_out;
  const int count = static_cast<int>(out->size());
  const int per_phase = (count + factor - 1) / factor;  // outputs of phase 0; others <= that
  phase_out.resize(static_cast<size_t>(per_phase));
  for (int phase = 0; phase < factor; ++phase) {
    const int outputs = (count - phase + factor - 1) / factor;
    float* __restrict acc = phase_out.data();
    std::fill(acc, acc + outputs, 0.0f);
    for (int t = 0; t < kSpan; ++t) {
      const float w = weights[static_cast<size_t>(phase) * kSpan + static_cast<size_t>(t)];
      const float* __restrict x = padded.data() + 1 + t;  // output b reads x[b]
#pragma omp simd
      for (int b = 0; b < outputs; ++b) acc[b] += w * x[b];
    }
    for (int b = 0; b < outputs; ++b)
      (*out)[static_cast<size_t>(b) * static_cast<size_t>(factor) + static_cast<size_t>(phase)] = acc[b];
  }
}

}  // namespace localizer::engine
