// Closure of a small array's pairs: a reference pair whose peak the other pairs contradict is
// measured where they agree.
//
// Why. A 4-sensor array's three reference pairs have an exact position through any one pair's
// wrong peak (an echo's cross term, a noise peak): the track follows it with every innovation
// small, and no test on the reference pairs can tell. The pairs without the reference
// (Measurement::cross_pairs) can: delays close, t_b - t_a = (t_b - t_0) - (t_a - t_0), so a
// cross pair (a, b) reads its peak at lag_b - lag_a when both reference peaks are right.
//
// How. For each usable reference pair p with at least two witnesses (cross pairs joining its
// sensor to another usable reference pair q), the consensus over lags x of p's window is
//     S_p(x) = n_p(x) + sum_q n_(p,q)(cross lag of x and lag_q)
// (normalised GCCs, lag_field.h: N(0, 1) per lag without a source). p's peak is contradicted
// when the best x lies more than kMinMoveSamples from its peak and S_p there beats S_p at the
// peak by more than kClosureMargin sqrt(1 + witnesses) (the sum's noise-only standard
// deviation). A pair is moved only when it is the frame's one contradicted pair (two
// contradicted pairs leave no majority of witnesses to trust):
//   - onto a peak of its own GCC near x (a local maximum within 2 samples, at least 3 noise
//     sds), refined by a parabola; its delay sigma is cleared (the session then sets it from
//     that peak's curvature at that peak's own height: OwnPeakSigmaS, pair_noise.h);
//   - else (its own peak smeared by the source's motion, or masked) onto the consensus's peak,
//     refined by a parabola, with sqrt(2) x the smallest witness's reference-pair sigma (the
//     witness's pair and its cross pair taken as equally precise); not moved when no witness
//     has a sigma.
// The moved pair is marked confirmed (measurement.h).
//
// A frame whose pairs agree is left exactly as it was. Cost: O(window) per pair to find each
// one's largest value; a reference pair is scanned (O(window x (1 + witnesses))) only when the
// sum of its terms' largest values could beat S_p at its peak by the margin. A few
// microseconds for a 4-sensor array; the cross pairs' measurement (one weighting and inverse
// FFT each) is the caller's: with it, 12-17 us per 4 x 4096 frame (BENCHMARKS.md).
#pragma once

#include <vector>

#include "engine/acquisition/lag_field.h"
#include "engine/core/measurement.h"

namespace localizer::engine {

struct ClosureRepair {
  int pair = -1;  // the moved reference pair's index in Measurement::pairs; -1: none
  double from_s = 0.0;
  double to_s = 0.0;
  double gain = 0.0;      // S_p at the new lag minus S_p at the old, in noise sds
  bool own_peak = false;  // moved onto a peak of its own GCC (else the consensus's)
  double sigma_s = 0.0;   // the delay sigma it was given (0: from its own peak's curvature)
};

// Holds its scratch between frames (one per session; not thread-safe).
class PairClosure {
 public:
  // Moves at most one reference pair of `m` (see above); m->cross_pairs must have been
  // measured (none: nothing to check, returns pair -1).
  ClosureRepair Repair(Measurement* m);

  // A cross pair (field pair `field_pair`) joining a reference pair's sensor to reference pair
  // `other`'s. Its lag at the reference pair's lag x is sign * (x - lag_other): +1 when the
  // reference pair's sensor is the cross pair's b, -1 when it is a.
  struct Witness {
    int field_pair = 0;
    int other = 0;
    double sign = 1.0;
  };

 private:
  LagField field_;
  std::vector<double> lags_;        // reference pairs' peaks, samples
  std::vector<double> largest_;     // each field pair's largest normalised value
  std::vector<Witness> witnesses_;  // the reference pair being checked
};

}  // namespace localizer::engine
