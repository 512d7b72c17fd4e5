// GccPhatEstimator's weighing of a pair's cross-spectrum (gcc_phat.h: PHAT, PHAT-beta, SCOT,
// CC, the learnt coherence and the frame's shares) and the noise-only scale of weights that
// are not PHAT's. Internal to engine/tdoa (gcc_phat_impl.h).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>

#include "engine/tdoa/cross_spectrum.h"
#include "engine/tdoa/gcc_phat_impl.h"

namespace localizer::engine {
namespace {
constexpr float kShareWeightCapInverse = 0.25f;  // the weight's cap, 4, inverted
}  // namespace

// The shares are read over every bin, not only the band a hint gives: a source that fills its
// band would otherwise be its own floor, and the weights would gather on its loudest bins
// (ACCURACY.md, "Thirty-first pass"). Only the band's bins are weighed.
void GccPhatEstimator::Impl::FindShares() {
  const int lo = layout.band_first_bin;
  const int hi = layout.band_end_bin;
  const int bins = layout.bin_count;
  bin_power.assign(static_cast<std::size_t>(bins), 0.0);
  for (int c = 0; c < array.sensor_count(); ++c) {
    const float* x = SpectrumOf(c);
    for (int b = 0; b < bins; ++b) {
      const double re = x[2 * b], im = x[2 * b + 1];
      bin_power[static_cast<std::size_t>(b)] += re * re + im * im;
    }
  }
  share_flat = share_finder.Find(bin_power);
  if (share_flat) return;
  const std::span<const double> shares = share_finder.shares();
  // The maximum-likelihood weight (Carter's |gamma|^2 / (1 - |gamma|^2), with the coherence
  // |gamma| of two channels each holding share s of signal equal to s) is s^2 / (1 - s^2):
  // noise bins, whose s is seldom above 0.3, weigh under a tenth of what s gave them, which
  // is what costs a narrow source in a wide band. Capped at 4 (s = 0.89) so a few loud bins,
  // a tone's, cannot carry the frame alone: with a cap of 10, multipath scenes with tones lost
  // their direct path 4x as often as with w = s (ACCURACY.md, "Thirty-first pass").
  for (int b = lo; b < hi; ++b) {
    const float s2 = static_cast<float>(shares[b] * shares[b]);
    share_weight[static_cast<std::size_t>(b)] = s2 / std::max(1.0f - s2, kShareWeightCapInverse);
  }
}

bool GccPhatEstimator::Impl::WeighedBeyondPhat(int pair) const {
  switch (options.weighting) {
    case Weighting::kPhatCoherence:
      return pair >= 0 && coherence_usable[pair];
    case Weighting::kPhatShare:
      return !share_flat;
    default:
      return false;
  }
}

float GccPhatEstimator::Impl::WeighCrossSpectrum(int pair, float* g) {
  return WeighSensors(array.reference_sensor(), array.sensor_of_pair(pair), pair, g);
}

// Fills g with G = W X_k conj(X_r) B for sensors r = ref, k = sensor and returns S, the sum
// of |G| over all N bins. `pair` picks kPhatCoherence's learnt weights (-1: plain PHAT);
// kPhatShare weighs every pair, cross pairs too, by this frame's shares (FindShares).
float GccPhatEstimator::Impl::WeighSensors(int ref, int sensor, int pair, float* g) {
  const float* xr = SpectrumOf(ref);
  const float* xk = SpectrumOf(sensor);
  // g's out-of-band bins stay zero from allocation (WeighBins writes only the band, the
  // packed inverse only reads): the sum below reads DC and Nyquist whether or not in band.
  const int bin_count = layout.bin_count;

  const double e_ref = energy[ref];
  const double e_sensor = energy[sensor];
  const float floor_mag = PowerFloor(std::sqrt(e_ref * e_sensor));
  const int lo = layout.band_first_bin;
  const int hi = layout.band_end_bin;
  float half_sum = 0.0f;
  switch (options.weighting) {
    case Weighting::kPhat:
      half_sum = WeighBins(xr, xk, lo, hi, PhatWeight{floor_mag}, g);
      break;
    case Weighting::kPhatBeta:
      half_sum = WeighBins(xr, xk, lo, hi, PhatBetaWeight{floor_mag, static_cast<float>(options.phat_beta)}, g);
      break;
    case Weighting::kScot:
      half_sum = WeighBins(xr, xk, lo, hi, ScotWeight{PowerFloor(e_ref), PowerFloor(e_sensor)}, g);
      break;
    case Weighting::kCc:
      half_sum = WeighBins(xr, xk, lo, hi, CcWeight{}, g);
      break;
    case Weighting::kPhatShare:
      if (!share_flat) {
        half_sum = WeighBins(xr, xk, lo, hi, CoherencePhatWeight{floor_mag, share_weight.data()}, g);
      } else {  // nothing to tell signal from noise this frame: PHAT
        half_sum = WeighBins(xr, xk, lo, hi, PhatWeight{floor_mag}, g);
      }
      break;
    case Weighting::kPhatCoherence:
      if (pair >= 0 && coherence_usable[pair]) {
        const float* w = coherence_weight.data() + static_cast<std::size_t>(pair) * bin_count;
        half_sum = WeighBins(xr, xk, lo, hi, CoherencePhatWeight{floor_mag, w}, g);
      } else {  // warming up: plain PHAT
        half_sum = WeighBins(xr, xk, lo, hi, PhatWeight{floor_mag}, g);
      }
      break;
  }
  // Bins 1..N/2-1 stand for two bins of the full spectrum; DC and Nyquist (real) for one.
  return 2.0f * half_sum - std::abs(g[0]) - std::abs(g[2 * (bin_count - 1)]);
}

// Noise alone gives each bin a uniform phase, so R(l) = (1/S) sum_k G_k e^{j w_k l} has
// variance (sum over interior bins of 2 |G_k|^2 + |G_0|^2 + |G_N/2|^2) / S^2: 1 / (2 B) for
// PHAT's B unit bins (the layout's constant), 1 / (2 B_eff) with B_eff = (sum w)^2 / sum w^2
// for other weights (learnt coherence, the frame's shares), which gather on a few bins and
// would otherwise read noise as a source many times over. Reads the pair's cross-spectrum g.
float GccPhatEstimator::Impl::WeighedNoiseFloorInverse(float norm, const float* g) const {
  const int lo = layout.band_first_bin;
  const int hi = layout.band_end_bin;
  const int last = layout.bin_count - 1;
  // Sum of squares over the band's interleaved floats, in independent lanes so it vectorises;
  // then DC and Nyquist (whose imaginary parts are 0) counted once.
  double lanes[kLanes] = {};
  const float* first = g + 2 * lo;
  const int count = 2 * (hi - lo);
  int i = 0;
  for (; i + kLanes <= count; i += kLanes) {
    for (int l = 0; l < kLanes; ++l) lanes[l] += static_cast<double>(first[i + l]) * first[i + l];
  }
  double power = 0.0;
  for (; i < count; ++i) power += static_cast<double>(first[i]) * first[i];
  for (double lane : lanes) power += lane;
  double variance = 2.0 * power;
  if (lo == 0) variance -= static_cast<double>(g[0]) * g[0];
  if (hi == last + 1) variance -= static_cast<double>(g[2 * last]) * g[2 * last];
  return variance > 0.0 ? layout.taper_noise_factor * static_cast<float>(norm / std::sqrt(variance)) : 0.0f;
}

}  // namespace localizer::engine
