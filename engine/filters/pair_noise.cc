#include "engine/filters/pair_noise.h"

#include <algorithm>
#include <cmath>

namespace localizer::engine {
namespace {
// Adaptive TDOA noise (fixed sigma 0): start at 0.1 sample, smooth over ~20 frames,
// keep within [0.01, 2] samples.
constexpr double kInitialSigmaSamples = 0.1;
constexpr double kSigmaSmoothing = 0.05;
constexpr double kMinSigmaSamples = 0.01;
constexpr double kMaxSigmaSamples = 2.0;
}  // namespace

int PairNoise::Select(const Measurement& m, double min_peak_snr) {
  if (sigmas_s_.size() != m.pairs.size()) {
    sigmas_s_.assign(m.pairs.size(),
                     fixed_sigma_s_ > 0.0 ? fixed_sigma_s_ : kInitialSigmaSamples / m.sample_rate_hz);
  }
  used_.resize(m.pairs.size());
  int count = 0;
  for (size_t p = 0; p < m.pairs.size(); ++p) {
    used_[p] = m.pairs[p].peak_snr >= min_peak_snr ? 1 : 0;
    count += used_[p];
  }
  return count;
}

void PairNoise::Finish(const std::vector<InnovationMoments>& innovations, double sample_rate_hz,
                       UpdateReport* report) {
  double mean_var_s2 = 0.0;
  for (size_t p = 0; p < innovations.size() && p < sigmas_s_.size(); ++p) {
    double& sigma_s = sigmas_s_[p];
    mean_var_s2 += sigma_s * sigma_s / static_cast<double>(sigmas_s_.size());
    if (!used_[p]) continue;
    const InnovationMoments& in = innovations[p];
    report->nis += in.mean_s * in.mean_s / (sigma_s * sigma_s + in.predicted_var_s2);
    if (fixed_sigma_s_ == 0.0) {  // innovation-based adaptive estimate (Mehra 1972), per pair
      const double excess_s2 = std::max(0.0, in.mean_s * in.mean_s - in.predicted_var_s2);
      const double var_s2 = (1.0 - kSigmaSmoothing) * sigma_s * sigma_s + kSigmaSmoothing * excess_s2;
      sigma_s = std::clamp(std::sqrt(var_s2), kMinSigmaSamples / sample_rate_hz, kMaxSigmaSamples / sample_rate_hz);
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
