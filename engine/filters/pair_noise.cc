#include "engine/filters/pair_noise.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace localizer::engine {
namespace {
constexpr double kSmoothing = 0.05;
constexpr double kMinScale = 0.5, kMaxScale = 8.0;
constexpr double kDivergenceScaleCap = 2.0;
constexpr double kGateSigmas = 4.0;
constexpr double kAnchoredCap = 6.0;  // |z| beyond this counts as 6 in the divergence test
constexpr double kMinAnchorSamples = 0.02;
constexpr double kStartSigmaSamples = 0.05;
constexpr double kMaxStartScale = 2.0;
constexpr double kConfirmedPeakSnr = 3.0;  // a confirmed pair's peak SNR floor
// The fallback without an anchor: start at 0.1 sample, keep within [0.01, 2] samples.
constexpr double kInitialSigmaSamples = 0.1;
constexpr double kMinSigmaSamples = 0.01;
constexpr double kMaxSigmaSamples = 2.0;
}  // namespace

double PeakSigmaS(const PairMeasurement& pair, double peak_snr, double sample_rate_hz) {
  if (pair.gcc.size() < 3 || !(peak_snr > 0.0) || !(sample_rate_hz > 0.0)) return 0.0;
  const long i = std::lround(pair.delay_s * sample_rate_hz) - pair.first_lag_samples;
  if (i < 1 || i + 1 >= static_cast<long>(pair.gcc.size())) return 0.0;
  const double g = pair.gcc[static_cast<size_t>(i)];
  const double curvature = 2.0 * g - pair.gcc[static_cast<size_t>(i - 1)] - pair.gcc[static_cast<size_t>(i + 1)];
  if (!(g > 0.0) || !(curvature > 0.0)) return 0.0;
  const double sigma_samples = 1.0 / (peak_snr * std::sqrt(curvature / g));
  return std::max(sigma_samples, kMinAnchorSamples) / sample_rate_hz;
}

double OwnPeakSigmaS(const PairMeasurement& pair, double sample_rate_hz) {
  if (!(pair.peak_value > 0.0) || !(sample_rate_hz > 0.0)) return 0.0;
  const long i = std::lround(pair.delay_s * sample_rate_hz) - pair.first_lag_samples;
  if (i < 0 || i >= static_cast<long>(pair.gcc.size())) return 0.0;
  const double height = pair.gcc[static_cast<size_t>(i)];
  return PeakSigmaS(pair, pair.peak_snr * (height / pair.peak_value), sample_rate_hz);
}

double AnchorSigmaS(const PairMeasurement& pair, double sample_rate_hz) {
  if (pair.delay_sigma_s > 0.0) return pair.delay_sigma_s;
  return PeakSigmaS(pair, pair.peak_snr, sample_rate_hz);
}

int PairNoise::Select(const Measurement& m, double min_peak_snr) {
  const size_t n = m.pairs.size();
  if (sigmas_s_.size() != n) {
    sigmas_s_.assign(n, 0.0);
    anchors_s_.assign(n, 0.0);
    scale2_.assign(n, 0.0);  // 0: not yet seen
    free_sigma_s_.assign(n, kInitialSigmaSamples / m.sample_rate_hz);
  }
  used_.resize(n);
  int count = 0;
  for (size_t p = 0; p < n; ++p) {
    const double needed = m.pairs[p].confirmed ? std::min(min_peak_snr, kConfirmedPeakSnr) : min_peak_snr;
    used_[p] = m.pairs[p].peak_snr >= needed ? 1 : 0;
    count += used_[p];
    if (fixed_sigma_s_ > 0.0) {
      anchors_s_[p] = sigmas_s_[p] = fixed_sigma_s_;
      continue;
    }
    anchors_s_[p] = AnchorSigmaS(m.pairs[p], m.sample_rate_hz);
    if (scale2_[p] == 0.0 && anchors_s_[p] > 0.0) {
      // Start at the anchor, or at kStartSigmaSamples if that is larger (the sub-sample
      // interpolation's bias) but at most kMaxStartScale anchors, and let the innovations
      // adapt it. Why at most 2: with Mehra's excess at 0 while the cloud is wider than the
      // innovations, the scale falls 5 % a frame, so a start at 8 anchors (a front end whose
      // spread is 0.006 sample) took 14 s to come down: the covariance too wide for that
      // long (campaign NEES 0.48 with phat-share; 0.55 with this cap, ACCURACY.md).
      const double start = kStartSigmaSamples / m.sample_rate_hz / anchors_s_[p];
      scale2_[p] = std::clamp(start * start, 1.0, kMaxStartScale * kMaxStartScale);
    }
    sigmas_s_[p] = anchors_s_[p] > 0.0 ? std::sqrt(scale2_[p]) * anchors_s_[p] : free_sigma_s_[p];
  }
  return count;
}

void PairNoise::Finish(const std::vector<InnovationMoments>& innovations, double sample_rate_hz, UpdateReport* report) {
  double mean_var_s2 = 0.0;
  report->anchored_z.assign(sigmas_s_.size(), std::numeric_limits<double>::quiet_NaN());
  // The divergence test's terms: signed, capped at kAnchoredCap sigmas.
  auto anchored = [&](size_t p, double e_s, double var_s2) {
    const double z = std::clamp(e_s / std::sqrt(var_s2), -kAnchoredCap, kAnchoredCap);
    report->anchored_z[p] = z;
    report->anchored_nis += z * z;
  };
  for (size_t p = 0; p < innovations.size() && p < sigmas_s_.size(); ++p) {
    const double sigma_s = sigmas_s_[p];
    mean_var_s2 += sigma_s * sigma_s / static_cast<double>(sigmas_s_.size());
    if (!used_[p]) continue;
    const InnovationMoments& in = innovations[p];
    const double e2 = in.mean_s * in.mean_s;
    report->nis += e2 / (sigma_s * sigma_s + in.predicted_var_s2);
    report->nis_terms.push_back({e2, sigma_s * sigma_s, in.predicted_var_s2});
    const double anchor_s = anchors_s_[p];
    if (fixed_sigma_s_ > 0.0) {
      anchored(p, in.mean_s, sigma_s * sigma_s + in.predicted_var_s2);
    } else if (anchor_s > 0.0) {
      const double capped = std::min(std::sqrt(scale2_[p]), kDivergenceScaleCap) * anchor_s;
      anchored(p, in.mean_s, capped * capped + in.predicted_var_s2);
      // Mehra on the normalised innovation, outliers gated out, and innovations whose excess
      // over the prior's spread no admissible noise gives (beyond the gate at the largest
      // scale): only a wrong prior explains those, e.g. a track converging from a wrong start.
      const double excess = std::max(0.0, e2 - in.predicted_var_s2) / (anchor_s * anchor_s);
      if (e2 <= kGateSigmas * kGateSigmas * (sigma_s * sigma_s + in.predicted_var_s2) &&
          excess <= kGateSigmas * kGateSigmas * kMaxScale * kMaxScale) {
        scale2_[p] =
            std::clamp(scale2_[p] + kSmoothing * (excess - scale2_[p]), kMinScale * kMinScale, kMaxScale * kMaxScale);
      }
    } else {
      anchored(p, in.mean_s, sigma_s * sigma_s + in.predicted_var_s2);
      const double excess_s2 = std::max(0.0, e2 - in.predicted_var_s2);
      const double var_s2 = (1.0 - kSmoothing) * sigma_s * sigma_s + kSmoothing * excess_s2;
      free_sigma_s_[p] =
          std::clamp(std::sqrt(var_s2), kMinSigmaSamples / sample_rate_hz, kMaxSigmaSamples / sample_rate_hz);
    }
  }
  report->tdoa_sigma_s = std::sqrt(mean_var_s2);
}

double PairNoise::rms_sigma_s() const {
  double sum_s2 = 0.0;
  for (double sigma_s : sigmas_s_) sum_s2 += sigma_s * sigma_s;
  return sigmas_s_.empty() ? 0.0 : std::sqrt(sum_s2 / static_cast<double>(sigmas_s_.size()));
}

}  // namespace localizer::engine
