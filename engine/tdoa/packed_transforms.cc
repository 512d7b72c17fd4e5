#include "engine/tdoa/packed_transforms.h"

#include <cstring>

namespace localizer::engine {

bool PackedTransforms::Init(int n, int first_bin, int end_bin, unsigned flags) {
  if (n < 2 || n % 2 != 0 || first_bin < 0 || end_bin <= first_bin || end_bin > n / 2 + 1) return false;
  n_ = n;
  first_bin_ = first_bin;
  end_bin_ = end_bin;
  const std::size_t floats = 2 * static_cast<std::size_t>(n);
  forward_in_ = AllocateFftwFloats(floats);
  forward_out_ = AllocateFftwFloats(floats);
  inverse_in_ = AllocateFftwFloats(floats);
  inverse_out_ = AllocateFftwFloats(floats);
  zeros_ = AllocateFftwFloats(2 * static_cast<std::size_t>(n / 2 + 1));
  forward_ = PlanComplex(n, forward_in_.get(), forward_out_.get(), FFTW_FORWARD, flags);
  inverse_ = PlanComplex(n, inverse_in_.get(), inverse_out_.get(), FFTW_BACKWARD, flags);
  // FFTW_MEASURE scribbles on the arrays while planning; the zeros the transforms rely on
  // (padding, out-of-band bins) must start at zero.
  std::memset(forward_in_.get(), 0, sizeof(float) * floats);
  std::memset(inverse_in_.get(), 0, sizeof(float) * floats);
  return forward_ && inverse_;
}

// The bins with a mirror (0 < k < n/2) in [first_bin, end_bin): [*interior_first, *interior_end).
void PackedTransforms::InteriorBins(int* interior_first, int* interior_end) const {
  *interior_first = first_bin_ > 0 ? first_bin_ : 1;
  *interior_end = end_bin_ < n_ / 2 ? end_bin_ : n_ / 2;
}

void PackedTransforms::Forward(float* spectrum_a, float* spectrum_b) {
  fftwf_execute(forward_.get());
  const float* z = forward_out_.get();
  // DC and Nyquist are their own mirrors: X_a the real part, X_b the imaginary.
  for (int k : {0, n_ / 2}) {
    if (k < first_bin_ || k >= end_bin_) continue;
    spectrum_a[2 * k] = z[2 * k];
    spectrum_a[2 * k + 1] = 0.0f;
    spectrum_b[2 * k] = z[2 * k + 1];
    spectrum_b[2 * k + 1] = 0.0f;
  }
  int first, end;
  InteriorBins(&first, &end);
  for (int k = first; k < end; ++k) {
    const int m = n_ - k;
    const float zr = z[2 * k], zi = z[2 * k + 1];
    const float mr = z[2 * m], mi = -z[2 * m + 1];  // conj Z(N - k)
    spectrum_a[2 * k] = 0.5f * (zr + mr);
    spectrum_a[2 * k + 1] = 0.5f * (zi + mi);
    spectrum_b[2 * k] = 0.5f * (zi - mi);
    spectrum_b[2 * k + 1] = -0.5f * (zr - mr);
  }
}

void PackedTransforms::Inverse(const float* g_a, const float* g_b) {
  float* z = inverse_in_.get();
  // Real bins: c2r ignores their imaginary parts.
  for (int k : {0, n_ / 2}) {
    if (k < first_bin_ || k >= end_bin_) continue;
    z[2 * k] = g_a != nullptr ? g_a[2 * k] : 0.0f;
    z[2 * k + 1] = g_b != nullptr ? g_b[2 * k] : 0.0f;
  }
  int first, end;
  InteriorBins(&first, &end);
  const float* a = g_a != nullptr ? g_a : zeros_.get();  // a missing spectrum reads as zeros
  const float* b = g_b != nullptr ? g_b : zeros_.get();
  for (int k = first; k < end; ++k) {
    const float ar = a[2 * k], ai = a[2 * k + 1];
    const float br = b[2 * k], bi = b[2 * k + 1];
    const int m = n_ - k;
    z[2 * k] = ar - bi;
    z[2 * k + 1] = ai + br;
    z[2 * m] = ar + bi;
    z[2 * m + 1] = br - ai;
  }
  fftwf_execute(inverse_.get());
}

}  // namespace localizer::engine
