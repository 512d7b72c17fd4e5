#include "engine/tdoa/signal_share.h"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace localizer::engine {

SignalShareOptions SignalShareOptionsForNoise(int channels, std::size_t floor_window_bins) {
  constexpr double kZ90 = 1.2815515655446004;  // the standard normal's 90th percentile
  constexpr double kZMax = 3.72;               // 1 % of frames, over ~100 independent windows
  constexpr double kOverMean = 1.35, kFlatMargin = 1.6;
  const auto wilson_hilferty = [](double k, double z) {  // Gamma(k)'s quantile over its mean
    const double c = 1.0 / (9.0 * k);                    // (X / k)^(1/3) ~ N(1 - c, c)
    return std::pow(1.0 - c + z * std::sqrt(c), 3.0);
  };
  const double k = std::max(1, channels) * static_cast<double>(floor_window_bins / 2 * 2 + 1);
  SignalShareOptions options;
  options.floor_window_bins = floor_window_bins;
  options.noise_over_floor = kOverMean / wilson_hilferty(k, -kZ90);
  options.flat_spread = kFlatMargin * wilson_hilferty(k, kZ90) / wilson_hilferty(k, -kZ90);
  options.flat_max_spread = kFlatMargin * wilson_hilferty(k / 2.0, kZMax) / wilson_hilferty(k / 2.0, -kZ90);
  return options;
}

void SignalShare::Smooth(std::span<const double> power, std::size_t window, std::vector<double>* out) const {
  const std::size_t n = power.size();
  out->assign(n, 0.0);
  const std::size_t half = window / 2;
  double sum = 0.0;
  std::size_t lo = 0, hi = 0;  // the window [lo, hi)
  for (std::size_t b = 0; b < n; ++b) {
    const std::size_t want_lo = b > half ? b - half : 0, want_hi = std::min(n, b + half + 1);
    while (hi < want_hi) sum += power[hi++];
    while (lo < want_lo) sum -= power[lo++];
    (*out)[b] = sum / static_cast<double>(hi - lo);
  }
}

bool SignalShare::Find(std::span<const double> power) {
  const std::size_t n = power.size();
  share_.assign(n, 1.0);
  flat_ = true;
  if (n == 0) return flat_;
  Smooth(power, options_.floor_window_bins, &smoothed_);
  sorted_ = smoothed_;
  const auto rank = static_cast<std::size_t>(options_.floor_quantile * static_cast<double>(n - 1));
  const auto at = [&](std::size_t r) { return sorted_.begin() + static_cast<std::ptrdiff_t>(r); };
  std::nth_element(sorted_.begin(), at(rank), sorted_.end());
  const double floor = sorted_[rank];
  if (options_.exact_upper_quantile) std::nth_element(at(rank), at(n - 1 - rank), sorted_.end());
  bool stands_out = !(sorted_[n - 1 - rank] < options_.flat_spread * floor);
  if (options_.flat_max_spread > 0.0 && !stands_out) {
    stands_out = !(*std::max_element(at(rank), sorted_.end()) < options_.flat_max_spread * floor);
  }
  flat_ = !(floor > 0.0 && stands_out);
  if (flat_) return flat_;
  if (options_.share_window_bins != options_.floor_window_bins) Smooth(power, options_.share_window_bins, &smoothed_);
  for (std::size_t b = 0; b < n; ++b) share_[b] = std::max(0.0, 1.0 - options_.noise_over_floor * floor / smoothed_[b]);
  return flat_;
}

}  // namespace localizer::engine
