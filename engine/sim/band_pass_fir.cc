#include "engine/sim/band_pass_fir.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "engine/sim/kaiser_window.h"

namespace localizer::engine {
namespace {

constexpr double kStopbandAttenuationDb = 60.0;
constexpr int kMinTaps = 63;
constexpr int kMaxTaps = 4095;  // bounds the cost for very narrow transitions

double Sinc(double x) {
  if (x == 0.0) return 1.0;
  const double pi_x = std::numbers::pi * x;
  return std::sin(pi_x) / pi_x;
}

// Half the narrowest feature of the band: the transitions then never overlap each other or
// reach DC or Nyquist.
double TransitionWidthHz(double low_hz, double high_hz, double sample_rate_hz) {
  double narrowest_hz = high_hz - low_hz;
  if (low_hz > 0.0) narrowest_hz = std::min(narrowest_hz, low_hz);
  const double above_hz = 0.5 * sample_rate_hz - high_hz;
  if (above_hz > 0.0) narrowest_hz = std::min(narrowest_hz, above_hz);
  return 0.5 * narrowest_hz;
}

int OddTapCount(double transition_hz, double sample_rate_hz) {
  const double width_rad = 2.0 * std::numbers::pi * transition_hz / sample_rate_hz;
  const double taps = (kStopbandAttenuationDb - 8.0) / (2.285 * width_rad) + 1.0;
  const int count = static_cast<int>(std::clamp(std::ceil(taps), double{kMinTaps}, double{kMaxTaps}));
  return count | 1;  // odd: a whole-sample group delay
}

}  // namespace

BandPassFir DesignBandPassFir(double band_low_hz, double band_high_hz, double sample_rate_hz) {
  BandPassFir fir;
  fir.transition_hz = TransitionWidthHz(band_low_hz, band_high_hz, sample_rate_hz);
  const int count = OddTapCount(fir.transition_hz, sample_rate_hz);
  const int half = (count - 1) / 2;
  const double beta = KaiserBetaForAttenuation(kStopbandAttenuationDb);
  const double high = 2.0 * band_high_hz / sample_rate_hz;  // cutoffs as fractions of fs/2
  const double low = 2.0 * band_low_hz / sample_rate_hz;
  fir.taps.resize(count);
  for (int n = 0; n < count; ++n) {
    const double offset = n - half;
    const double ideal = high * Sinc(high * offset) - low * Sinc(low * offset);
    fir.taps[n] = ideal * KaiserWindow(offset / half, beta);
  }
  return fir;
}

std::vector<double> FilterValid(const std::vector<double>& x, const std::vector<double>& taps) {
  const auto tap_count = static_cast<Eigen::Index>(taps.size());
  const auto out_count = static_cast<Eigen::Index>(x.size()) - tap_count + 1;
  std::vector<double> y(std::max<Eigen::Index>(out_count, 0));
  const Eigen::Map<const Eigen::VectorXd> h(taps.data(), tap_count);
  // Eigen's dot product runs on SIMD packets; a plain loop would not vectorise the reduction
  // because the build keeps strict floating-point association.
  for (Eigen::Index n = 0; n < out_count; ++n) {
    y[n] = h.dot(Eigen::Map<const Eigen::VectorXd>(x.data() + n, tap_count));
  }
  return y;
}

std::vector<double> UnitPowerBandNoise(double band_low_hz, double band_high_hz, double sample_rate_hz, int64_t n,
                                       std::mt19937_64* rng) {
  const BandPassFir fir = DesignBandPassFir(band_low_hz, band_high_hz, sample_rate_hz);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<double> white(static_cast<size_t>(n) + fir.taps.size() - 1);
  for (double& v : white) v = gauss(*rng);
  std::vector<double> out = FilterValid(white, fir.taps);
  double energy = 0.0;
  for (double h : fir.taps) energy += h * h;
  const double scale = energy > 0.0 ? 1.0 / std::sqrt(energy) : 0.0;
  for (double& v : out) v *= scale;
  return out;
}

}  // namespace localizer::engine
