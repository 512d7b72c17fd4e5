#include "gpu/tdoa/gcc_pair_measurement.h"

#include "engine/tdoa/peak_math.h"

namespace localizer::gpu {

void FillPairMeasurement(const GccPlan& plan, int pair, const GccPairResult& result, const float* window,
                         GccPairTail* tail, engine::PairMeasurement* out) {
  const engine::GccOptions& options = plan.options();
  const engine::GccLayout& layout = plan.layout();
  const int max_lag = layout.max_lag_samples[pair];
  const int count = 2 * max_lag + 1;
  // R at lags -L..L, with kPeakHalfWidth lags either side readable (the candidates' refinement).
  const float* searched = window != nullptr ? window + engine::kPeakHalfWidth : nullptr;
  out->sensor = plan.sensor_of_pair(pair);
  out->first_lag_samples = -max_lag;
  tail->padded.clear();
  if (!(result.norm > 0.0f)) {
    out->delay_s = 0.0;
    out->quality = 0.0;
    out->peak_value = 0.0;
    out->peak_snr = 0.0;
    out->delay_sigma_s = engine::SigmaCapSamples(max_lag) / options.sample_rate_hz;
    out->candidates.clear();
  } else {
    out->delay_s = (result.peak_lag + result.offset_samples) / options.sample_rate_hz;
    out->peak_value = result.peak_value;
    out->peak_snr = result.peak_value * layout.noise_floor_inverse;
    out->quality = result.quality;
    const engine::SpectrumMoments moments{result.level, result.first, result.curvature, result.slope_var};
    const double padding_factor = static_cast<double>(layout.fft_size) / options.frame_samples;
    tail->spread = engine::SpreadFromMoments(moments, result.norm, padding_factor, result.floor_samples, max_lag);
    tail->peak_index = result.peak_lag + max_lag;
    out->delay_sigma_s = tail->spread.sigma_samples / options.sample_rate_hz;
    // The main peak alone; without a window (keep_gcc off) it stays so.
    engine::PickDelayCandidates({}, tail->peak_index, max_lag, tail->spread, options.interpolation,
                                options.sample_rate_hz, 1, nullptr, out);
    if (window != nullptr) tail->padded.assign(window, window + count + 2 * engine::kPeakHalfWidth);
  }
  if (searched != nullptr) {
    out->gcc.assign(searched, searched + count);
  } else {
    out->gcc.clear();
  }
}

void FinishCandidates(const GccPlan& plan, std::span<const GccPairTail> tails, engine::Measurement* out,
                      std::vector<engine::WindowExtremum>* scratch) {
  const engine::GccOptions& options = plan.options();
  for (std::size_t p = 0; p < tails.size() && p < out->pairs.size(); ++p) {
    const GccPairTail& tail = tails[p];
    engine::PairMeasurement& pair = out->pairs[p];
    if (tail.padded.empty() || pair.candidates.empty()) continue;
    const int kept = static_cast<int>(tail.padded.size()) - 2 * engine::kPeakHalfWidth;
    engine::PickDelayCandidates(std::span<const float>(tail.padded.data() + engine::kPeakHalfWidth, kept),
                                tail.peak_index, (kept - 1) / 2, tail.spread, options.interpolation,
                                options.sample_rate_hz, options.max_candidates, scratch, &pair);
  }
}

}  // namespace localizer::gpu
