// GccPhatEstimator's per-peak statistics (gcc_phat.h): one pass over the kept cross-spectrum
// at the measured delay (the moments behind delay_sigma and the candidates' spacing,
// delay_statistics.h) and the PHAT-coherence weights it learns.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>

#include "engine/tdoa/cross_spectrum.h"
#include "engine/tdoa/gcc_phat_impl.h"

namespace localizer::engine {

// One pass over the in-band bins of the kept cross-spectrum, rotated to the measured delay
// d: A_k = G_k exp(j w_k d) = Re_k + j Im_k, w_k = 2 pi k / N (rad/sample), c_k = 2 for
// the bins that stand for a conjugate pair and 1 for DC and Nyquist. With kPhatCoherence it
// also folds this frame's aligned coherence Re(X_k X_r* e^{j w_k d}) / |X_k X_r*| into the
// pair's running average.
SpectrumMoments GccPhatEstimator::Impl::AnalyseSpectrum(int pair, double delay_samples, const float* g) {
  const int n = layout.fft_size;
  const int lo = layout.band_first_bin;
  const int hi = layout.band_end_bin;
  const double bin_rate = 2.0 * std::numbers::pi / n;
  const float* xr = SpectrumOf(array.reference_sensor());
  const float* xk = SpectrumOf(array.sensor_of_pair(pair));
  const bool learn = options.weighting == Weighting::kPhatCoherence;
  float* average = learn ? coherence.data() + static_cast<std::size_t>(pair) * layout.bin_count : nullptr;
  const float alpha = static_cast<float>(1.0 / options.coherence_time_constant_frames);
  const double step_angle = bin_rate * delay_samples;
  SpectrumMoments stats;
  // The phasor exp(j w_k d) in kLanes independent lanes (lane l at bin first + l), each
  // rotated by exp(j kLanes w_1 d) per block so that the loop vectorises; restarted exactly
  // every 2048 bins (the recurrence then drifts by < 1e-12). Lane sums, reduced at the end.
  constexpr int kRestart = 2048;
  static_assert(kRestart % kLanes == 0);
  const double block_re = std::cos(step_angle * kLanes);
  const double block_im = std::sin(step_angle * kLanes);
  double ph_re[kLanes], ph_im[kLanes];
  double level[kLanes] = {}, first_moment[kLanes] = {}, curvature[kLanes] = {}, slope[kLanes] = {};
  for (int first = lo; first < hi; first += kRestart) {
    const int last = std::min(first + kRestart, hi);
    for (int l = 0; l < kLanes; ++l) {
      ph_re[l] = std::cos(step_angle * (first + l));
      ph_im[l] = std::sin(step_angle * (first + l));
    }
    for (int b = first; b < last; b += kLanes) {
      const int count = std::min(kLanes, last - b);
      // One bin's moments; the full-width call has a constant trip count and vectorises.
      const auto accumulate = [&](int l) {
        const int k = b + l;
        const double gr = g[2 * k];
        const double gi = g[2 * k + 1];
        const double re = gr * ph_re[l] - gi * ph_im[l];
        const double im = gr * ph_im[l] + gi * ph_re[l];
        const double w = bin_rate * k;
        level[l] += re;
        first_moment[l] += w * re;
        curvature[l] += w * w * re;
        slope[l] += w * w * im * im;
      };
      if (count == kLanes) {
        for (int l = 0; l < kLanes; ++l) accumulate(l);
      } else {
        for (int l = 0; l < count; ++l) accumulate(l);
      }
      if (learn) {  // from the unweighted spectra: a bin weighted to zero must still learn
        for (int l = 0; l < count; ++l) {
          const int k = b + l;
          const CrossBin x = CrossAt(xr, xk, k);
          const double mag = std::sqrt(static_cast<double>(x.re) * x.re + static_cast<double>(x.im) * x.im);
          const double x_re = x.re * ph_re[l] - x.im * ph_im[l];
          const float aligned = mag > 0.0 ? static_cast<float>(x_re / mag) : 0.0f;
          average[k] += alpha * (aligned - average[k]);
        }
      }
      for (int l = 0; l < kLanes; ++l) {
        const double next_re = ph_re[l] * block_re - ph_im[l] * block_im;
        ph_im[l] = ph_re[l] * block_im + ph_im[l] * block_re;
        ph_re[l] = next_re;
      }
    }
  }
  for (int l = 0; l < kLanes; ++l) {
    stats.level += 2.0 * level[l];
    stats.first += 2.0 * first_moment[l];
    stats.curvature += 2.0 * curvature[l];
    stats.slope_var += 4.0 * slope[l];
  }
  // DC and Nyquist stand for one bin, not two: take back the excess (c_k = 1, c_k^2 = 1).
  for (int k : {0, n / 2}) {
    if (k < lo || k >= hi) continue;
    const double angle = step_angle * k;
    const double re = g[2 * k] * std::cos(angle) - g[2 * k + 1] * std::sin(angle);
    const double im = g[2 * k] * std::sin(angle) + g[2 * k + 1] * std::cos(angle);
    const double w = bin_rate * k;
    stats.level -= re;
    stats.first -= w * re;
    stats.curvature -= w * w * re;
    stats.slope_var -= 3.0 * w * w * im * im;
  }
  return stats;
}

// After a frame has been folded in: w = c^2 / (1 - c^2) from the bias-corrected average c
// (clamped to [0, 0.98]) for the pair's next frame.
void GccPhatEstimator::Impl::LearnCoherence(int pair) {
  const int frames = ++coherence_frames[pair];
  const double alpha = 1.0 / options.coherence_time_constant_frames;
  const double keep = 1.0 - alpha;
  // An average started at zero holds sum_w = 1 - keep^frames of the weight: divide it out.
  const double sum_w = 1.0 - std::pow(keep, frames);
  const double sum_w2 = alpha * alpha * (1.0 - std::pow(keep, 2 * frames)) / (1.0 - keep * keep);
  const int h = options.coherence_smoothing_bins;
  const int lo = layout.band_first_bin;
  const int hi = layout.band_end_bin;
  // A noise-only bin's aligned coherence is cos of a uniform phase: mean 0, variance 1/2. The
  // averaged, smoothed estimate then has variance v0 = (1/2) (sum_w2 / sum_w^2) / n_eff, n_eff
  // the independent bins in the 2h + 1 smoothed (zero padding correlates N / M neighbours):
  // c^2 is debiased by v0 so that noise-only bins get weight ~0 rather than ~v0.
  const double padding = static_cast<double>(layout.fft_size) / options.frame_samples;
  const double n_eff = std::max(1.0, (2.0 * h + 1.0) / padding);
  const float v0 = static_cast<float>(0.5 * sum_w2 / (sum_w * sum_w) / n_eff);
  const float correction = static_cast<float>(1.0 / sum_w);
  const std::size_t base = static_cast<std::size_t>(pair) * layout.bin_count;
  const float* average = coherence.data() + base;
  float* weight = coherence_weight.data() + base;
  // Box average over [k - h, k + h] within the band, by a running sum (double: no drift).
  double running = 0.0;
  int first = lo;
  int last = lo;  // the sum covers [first, last)
  float largest = 0.0f;
  for (int k = lo; k < hi; ++k) {
    while (last < std::min(hi, k + h + 1)) running += average[last++];
    while (first < k - h) running -= average[first++];
    const float c = std::max(0.0f, static_cast<float>(running / (last - first)) * correction);
    const float c2 = std::clamp(c * c - v0, 0.0f, 0.98f);
    weight[k] = c2 / (1.0f - c2);
    largest = std::max(largest, weight[k]);
  }
  coherence_usable[pair] = frames >= options.coherence_warmup_frames && largest > 1e-6f;
}

}  // namespace localizer::engine
