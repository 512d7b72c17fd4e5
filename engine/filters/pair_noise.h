// The per-pair TDOA noise a filter assumes, and the update's consistency numbers.
// Shared by the CPU filters (particle, Kalman, IMM, multiple-model) and the GPU particle
// filter (gpu/backend), so all choose pairs, set sigma and compute the NIS identically.
//
// Select marks the pairs whose peak_snr >= min_peak_snr (the others carry no source), or
// >= 3 for a pair the session confirmed near its track (PairMeasurement::confirmed).
//
// Anchored noise (the default, fixed sigma 0). Each frame's pair says how precise its own
// peak is: anchor_k = delay_sigma_s when the front end reports it (or the session's
// association or closure repair, for a smaller peak it measured the pair at: OwnPeakSigmaS,
// that peak's own SNR), else, when the frame kept its GCC, 1 / (peak_snr sqrt(-g''/g))
// samples from the GCC's height g and curvature g'' at the peak (the delay's Cramér–Rao-type
// bound for the PHAT peak; floored at 0.02 sample).
// The filter uses sigma_k = s_k anchor_k, where the scale s_k adapts to what the
// innovations show (Mehra's estimate on the normalised innovation, a = 0.05, starting where
// sigma = max(anchor, 0.05 sample) but at most 2 anchors: a start at 0.1 sample let a particle
// cloud spread along a weakly observed direction (range, at a few apertures) faster than the
// scale came down, 40 m in 6 s on one campaign scene; one at the anchor itself (down to 0.02
// sample) slowed the multiple-model particle filter's convergence 1.6x; one at 8 anchors kept
// a precise front end's covariance too wide for 14 s)
//     x_k = max(0, (e_k^2 - Var[h_k']) / anchor_k^2),   s_k^2 <- s_k^2 + a (x_k - s_k^2),
// kept within [0.5, 8] and fed only by innovations inside a 4-sigma gate (an outlier is an
// outlier, not noise) whose excess x_k some admissible noise could give, x_k <= (4 x 8)^2:
// beyond that only a wrong prior explains the innovation, e.g. a track converging from a
// wrong start whose cloud spreads the delays by milliseconds (one such frame used to set the
// scale to 8, where it stayed ~10 s while the track, weighing its pairs 8 times too little,
// ran off in range: campaign scene 7000013). So the adaptation can absorb a model that is
// several times too optimistic (multipath biases peaks beyond their curvature's
// bound), never a divergence: the divergence test caps the scale at 2 (below). Without an anchor (no GCC and no
// delay_sigma_s) the pair falls back to the former absolute adaptation: sigma from 0.1 sample, kept within [0.01, 2]
// samples. A fixed sigma (> 0) is used as it is, for every pair.
//
// Finish folds the innovation moments (e = d - E[h'], Var[h'] under the prior) into
//     nis          = sum_used e^2 / (sigma_k^2 + Var[h'])     (what the filter assumed)
//     anchored_nis = sum_used e^2 / (min(s_k, 2)^2 anchor_k^2 + Var[h'])
// the divergence test's input: the noise the peaks themselves allow, with at most a factor 2
// of adaptation, so that adaptation cannot hide a divergence.
#pragma once

#include <vector>

#include "engine/core/measurement.h"
#include "engine/filters/tracker.h"

namespace localizer::engine {

struct InnovationMoments {
  double mean_s = 0.0;            // d - E[h'] under the prior weights
  double predicted_var_s2 = 0.0;  // Var[h'] under the prior weights
};

// The anchor of one pair for one frame (seconds): delay_sigma_s if set, else from the kept
// GCC's peak; 0 when neither is available.
double AnchorSigmaS(const PairMeasurement& pair, double sample_rate_hz);
// 1 / (peak_snr sqrt(-g''/g)) at the kept GCC's integer lag nearest delay_s (seconds, floored
// at 0.02 sample); 0 without a GCC there or a peak. For a peak other than the tallest, pass
// its own SNR (the tallest's peak_snr times its height over peak_value).
double PeakSigmaS(const PairMeasurement& pair, double peak_snr, double sample_rate_hz);
// PeakSigmaS of the peak at delay_s at its own SNR: peak_snr times the kept GCC's height there
// over peak_value. For a pair measured at a peak other than its tallest (the session's
// association and closure repair); 0 without a GCC there.
double OwnPeakSigmaS(const PairMeasurement& pair, double sample_rate_hz);

class PairNoise {
 public:
  // fixed_sigma_s > 0: every pair uses it; 0: anchored and adaptive (above).
  explicit PairNoise(double fixed_sigma_s) : fixed_sigma_s_(fixed_sigma_s) {}

  // Sizes the state to the measurement's pairs on first use, marks the usable pairs, sets
  // this frame's sigmas and returns how many pairs are usable (0: the update should change
  // nothing).
  int Select(const Measurement& m, double min_peak_snr);
  // NIS and anchored NIS into report, the assumed noise (rms over pairs) into
  // report->tdoa_sigma_s, then adapts the scales. `innovations` has one entry per pair.
  void Finish(const std::vector<InnovationMoments>& innovations, double sample_rate_hz, UpdateReport* report);

  const std::vector<int>& used() const { return used_; }
  // This frame's sigma per pair (after Select).
  const std::vector<double>& sigmas_s() const { return sigmas_s_; }
  // Root mean square of the pairs' sigmas (0 before the first update).
  double rms_sigma_s() const;

 private:
  double fixed_sigma_s_;
  std::vector<double> sigmas_s_;      // this frame's
  std::vector<double> anchors_s_;     // this frame's (0: none)
  std::vector<double> scale2_;        // adapted s_k^2 (anchored pairs)
  std::vector<double> free_sigma_s_;  // fallback absolute adaptation (pairs without anchor)
  std::vector<int> used_;
};

}  // namespace localizer::engine
