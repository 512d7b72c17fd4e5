// Band-limited upsampling of a GCC window, so a tracker can read it between integer lags
// without the bias of low-order interpolation (a parabola or a cubic through integer lags
// moves a GCC-PHAT peak by up to ~0.1 sample, as much as the TDOA noise itself).
//
// out[j] = sum_m g[m] k(j / factor - m), k(x) = sinc(x) (0.5 + 0.5 cos(pi x / kTaps)) for
// |x| < kTaps (a Hann-windowed sinc), j = 0 .. (size - 1) * factor; out[j * factor] = g[j].
// Cost: (size * factor) * 2 kTaps multiply-adds; reuses `out`'s storage.
#pragma once

#include <vector>

namespace localizer::engine {

inline constexpr int kGccUpsampleTaps = 8;

void UpsampleGcc(const std::vector<float>& gcc, int factor, std::vector<float>* out);

}  // namespace localizer::engine
