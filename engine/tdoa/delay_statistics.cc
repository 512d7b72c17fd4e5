#include "engine/tdoa/delay_statistics.h"

#include <algorithm>
#include <array>

namespace localizer::engine {

DelaySpread SpreadFromMoments(const SpectrumMoments& moments, float norm, double padding_factor, double floor_samples,
                              int max_lag) {
  DelaySpread spread;
  // delay_sigma (gcc_phat.h): sigma = sqrt((N / M) sum c^2 w^2 Im^2) / sum c w^2 Re.
  spread.slope_std = std::sqrt(padding_factor * moments.slope_var) / norm;
  const double cap = SigmaCapSamples(max_lag);
  spread.sigma_samples = cap;
  if (moments.curvature > 0.0) {
    const double stat = spread.slope_std / (moments.curvature / norm);
    spread.sigma_samples = std::min(std::sqrt(stat * stat + floor_samples * floor_samples), cap);
  }
  // The rms width of the aligned spectrum sets the envelope's first null.
  const double searched_count = 2.0 * max_lag + 1.0;
  if (moments.level > 0.0) {
    const double mean = moments.first / moments.level;
    const double var = moments.curvature / moments.level - mean * mean;
    if (var > 0.0) spread.radius_lags = std::clamp(kEnvelopeNullPerRmsWidth / std::sqrt(var), 1.0, searched_count);
  }
  return spread;
}

void PickDelayCandidates(std::span<const float> searched, int peak, int max_lag, const DelaySpread& spread,
                         PeakInterpolation interpolation, double sample_rate_hz, int max_candidates,
                         std::vector<WindowExtremum>* scratch, PairMeasurement* out) {
  out->candidates.resize(1);
  out->candidates[0] = DelayCandidate{out->delay_s, out->peak_value, out->delay_sigma_s};
  if (max_candidates <= 1) return;  // the main peak alone: no scan of the window's extrema
  const int count = static_cast<int>(searched.size());
  const double cap = SigmaCapSamples(max_lag);
  const float* w = searched.data();  // w[-K .. count - 1 + K] are valid
  const auto sigma_of = [&](double curvature, double floor) {
    if (!(curvature < 0.0)) return cap;
    const double stat = spread.slope_std / -curvature;
    return std::min(std::sqrt(stat * stat + floor * floor), cap);
  };
  std::vector<WindowExtremum>& extrema = *scratch;
  extrema.clear();
  for (int i = 0; i < count; ++i) {
    if (i == peak) continue;
    const float v = w[i];
    const bool is_max = v > 0.0f && v > w[i - 1] && v >= w[i + 1];
    const bool is_min = v < 0.0f && v < w[i - 1] && v <= w[i + 1];
    if (is_max || is_min) extrema.push_back({std::abs(v), i});
  }
  std::sort(extrema.begin(), extrema.end(), [](const WindowExtremum& a, const WindowExtremum& b) {
    return a.magnitude != b.magnitude ? a.magnitude > b.magnitude : a.index < b.index;
  });
  std::array<int, kMaxCandidates> taken{};
  taken[0] = peak;
  int taken_count = 1;
  const int wanted = std::min(max_candidates, kMaxCandidates);
  for (const WindowExtremum& e : extrema) {
    if (taken_count >= wanted) break;
    bool clear = true;
    for (int t = 0; t < taken_count; ++t) clear = clear && std::abs(e.index - taken[t]) >= spread.radius_lags;
    if (!clear) continue;
    taken[taken_count++] = e.index;
    std::array<float, kPeakSamples> around{};
    const float sign = w[e.index] < 0.0f ? -1.0f : 1.0f;
    for (int m = 0; m < kPeakSamples; ++m) around[m] = sign * w[e.index - kPeakHalfWidth + m];
    const double offset = InterpolatePeak(interpolation, around);
    DelayCandidate candidate;
    candidate.delay_s = (e.index - max_lag + offset) / sample_rate_hz;
    candidate.value = w[e.index];
    candidate.delay_sigma_s =
        sigma_of(SincCurvature(around, offset), InterpolationErrorSamples(interpolation, around, offset)) /
        sample_rate_hz;
    out->candidates.push_back(candidate);
  }
}

}  // namespace localizer::engine
