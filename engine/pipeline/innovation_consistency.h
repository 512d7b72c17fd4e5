// How much a position estimate's covariance must grow to match what its innovations show
// (Estimate::covariance): an estimate never claims more certainty than the data gives.
//
// A consistent filter's normalised innovation squared (NIS) averages the number of pairs it
// used. When the last kFrames frames' NIS, summed, exceeds their pairs, summed, by a ratio
// r > 1, the measurements disagree with the track by r times what its noise model allows:
// a peak locked on a tonal sidelobe or a reflection that the filter follows, or a model too
// optimistic. The reported covariance is then multiplied by r (covariance matching, as in
// Mehra's adaptive filtering), not the filter's own: the track keeps its state, the user sees
// the doubt. Measured on the random scene campaign (ACCURACY.md, seed 5): estimates off by
// more than 10 x the per-frame CRLB while claiming a position NEES above 50 for over a
// second ("silent failures") had frames with NIS 3-14 x their pairs.
//
// Multiplying the whole covariance by r understates the doubt when the filter's own spread is
// small beside the measurement noise (a converged track that lags a turn): the NIS's terms
// e_p^2 / (sigma_p^2 + Var[h_p]) are then bounded by the noise, while the state is off by
// many of its own sds. So when the frames' NIS is significant (above the chi-square 0.99
// quantile of their pairs) and the filter gave its terms, the inflation is at least the k
// that makes the innovations consistent with the state's spread scaled alone:
//     sum_p e_p^2 / (sigma_p^2 + k Var[h_p]) = sum pairs,   1 <= k <= kMaxInflation.
// Measured on the campaign (ACCURACY.md, "Tenth pass").
#pragma once

#include <array>
#include <vector>

#include "engine/filters/tracker.h"

namespace localizer::engine {

class InnovationConsistency {
 public:
  static constexpr int kFrames = 4;
  static constexpr double kMaxInflation = 1e4;  // sd x 100
  // One updated frame's NIS and the pairs it used (> 0), with its terms when the filter
  // gives them (UpdateReport::nis_terms; empty: the ratio alone).
  void Add(double nis, int pairs, const std::vector<UpdateReport::NisTerm>& terms = {});
  // max(1, sum NIS / sum pairs) over the last kFrames frames, or the state's share above
  // when larger; 1 before any.
  double Inflation() const;
  void Reset() { count_ = 0; }

 private:
  std::array<double, kFrames> nis_{};
  std::array<int, kFrames> pairs_{};
  std::array<std::vector<UpdateReport::NisTerm>, kFrames> terms_;
  int count_ = 0;  // frames added since the reset (the ring holds min(count_, kFrames))
};

}  // namespace localizer::engine
