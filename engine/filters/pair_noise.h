// The per-pair TDOA noise a particle filter assumes, and the update's consistency numbers.
// Shared by the CPU particle filter and the GPU one (gpu/backend), so both choose pairs,
// adapt sigma and compute the NIS identically.
//
// Per update: Select marks the pairs whose peak_snr >= min_peak_snr (the others carry no
// source); the filter weighs with sigmas_s(); Finish folds the pairs' innovation moments
// (d - E[h'] and Var[h'] under the prior) into the NIS,
//     nis = sum_used (d - E[h'])^2 / (sigma^2 + Var[h']),
// and, when no fixed sigma was configured, adapts each used pair's sigma by Mehra's
// innovation-based estimate: sigma^2 <- (1 - a) sigma^2 + a max(0, e^2 - Var[h']), a = 0.05,
// starting at 0.1 sample and kept within [0.01, 2] samples.
#pragma once

#include <vector>

#include "engine/core/measurement.h"
#include "engine/filters/tracker.h"

namespace localizer::engine {

struct InnovationMoments {
  double mean_s = 0.0;            // d - E[h'] under the prior weights
  double predicted_var_s2 = 0.0;  // Var[h'] under the prior weights
};

class PairNoise {
 public:
  // fixed_sigma_s > 0: every pair uses it; 0: adaptive per pair (above).
  explicit PairNoise(double fixed_sigma_s) : fixed_sigma_s_(fixed_sigma_s) {}

  // Sizes the sigmas to the measurement's pairs on first use, marks the usable pairs and
  // returns how many there are (0: the update should change nothing).
  int Select(const Measurement& m, double min_peak_snr);
  // NIS into report->nis, the assumed noise (rms over pairs, before adapting) into
  // report->tdoa_sigma_s, then adapts the sigmas. `innovations` has one entry per pair.
  void Finish(const std::vector<InnovationMoments>& innovations, double sample_rate_hz, UpdateReport* report);

  const std::vector<int>& used() const { return used_; }
  const std::vector<double>& sigmas_s() const { return sigmas_s_; }
  // Root mean square of the pairs' sigmas (0 before the first update).
  double rms_sigma_s() const;

 private:
  double fixed_sigma_s_;
  std::vector<double> sigmas_s_;
  std::vector<int> used_;
};

}  // namespace localizer::engine
