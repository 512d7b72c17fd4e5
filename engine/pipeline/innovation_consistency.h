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
#pragma once

#include <array>

namespace localizer::engine {

class InnovationConsistency {
 public:
  static constexpr int kFrames = 4;
  // One updated frame's NIS and the pairs it used (> 0).
  void Add(double nis, int pairs);
  // max(1, sum NIS / sum pairs) over the last kFrames frames; 1 before any.
  double Inflation() const;
  void Reset() { count_ = 0; }

 private:
  std::array<double, kFrames> nis_{};
  std::array<int, kFrames> pairs_{};
  int count_ = 0;  // frames added since the reset (the ring holds min(count_, kFrames))
};

}  // namespace localizer::engine
