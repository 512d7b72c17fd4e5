// Every measured pair's peak folded into the reference pairs' delays: the sensors' delays
// that best explain all of a frame's pairs, by weighted least squares.
//
// Why. A tracker reads the M - 1 reference pairs (reference, k). Their GCC errors are nearly
// independent of each other on the campaign's scenes (PHAT whitens the band's noise, so the
// noise x noise terms dominate: the reference pairs' errors correlate by -0.02 to -0.03 on
// 7-sensor scenes), so the pairs without the reference (Measurement::cross_pairs, the other
// (M - 1)(M - 2) / 2) carry evidence of their own: t_b - t_a = (t_b - t_0) - (t_a - t_0). With
// equal, independent pair errors the least-squares delays of a complete graph of M sensors
// have 2 / M of one pair's variance (the effective resistance between two nodes).
//
// How. Unknowns: x_k, sensor k's delay after the reference's, for the usable reference pairs
// (delay_sigma_s > 0, a kept GCC, peak_snr >= kMinPeakSnr or confirmed). Each of them is an
// edge d_k = x_k; each cross pair (a, b) joining two of them is an edge d_ab = x_b - x_a when
// its GCC has a local maximum of at least kMinCrossPeak noise sds within the lags the two
// reference peaks predict (x_b - x_a, +- 3 sd of that prediction, 1-3 samples). Each peak is
// sinc-refined like the front end's (a cross pair reads the lags beyond its window,
// CrossPairGcc::gcc_beyond; a peak that would need more is left out, since a parabola is biased
// by up to 0.06 sample). Edge weights are 1 / sigma^2: the reference pairs' delay_sigma_s; for
// a cross pair, the quadratic-peak bound's shape 1 / sqrt(g (-g'')) of its normalised GCC at
// the peak, times the frame's median of delay_sigma_s over that shape among the reference
// pairs whose peak lies 8 samples inside their window (none: the rms of its two reference
// pairs' sigmas). The normal equations are solved (Cholesky); an
// edge more than kOutlierSigmas of its sigma from the solution is dropped and the system
// solved again (at most three rounds of drops), so one pair on a wrong peak is outvoted rather than
// spread. Each usable reference pair then takes delay_s = x_k and its candidates[0] too.
//
// Sigma. The least-squares variance (A^-1)_kk (A the normal matrix) holds where the pairs'
// errors are independent, i.e. where noise x noise terms dominate the GCC. Where the source
// dominates (high SNR) each pair's error is mostly its two sensors' noise against the signal,
// which closes around every loop of pairs: the cross pairs then add little, and the
// least-squares variance would claim up to M / 2 times too little (on 48-kHz air scenes with
// 17 dB this put a track 10+ CRLBs off at position NEES > 50 for 1.2 s). The share f of the
// error that does not close is what the residuals show: chi^2 per degree of freedom of the
// kept edges (expected 1 when independent, 0 when every loop closes), clamped to [0, 1] and
// averaged over frames (kShareSmoothing). delay_sigma_s^2 = f (A^-1)_kk + (1 - f) sigma_k^2,
// sigma_k the pair's own. The fused delays' errors also correlate (about +1/2 with equal
// pairs); the filters' adaptive noise (pair_noise.h) absorbs what an independent likelihood
// then overstates.
//
// Instants. Pair (a, b) describes the emission that reached sensor a at t - d_ab / 2 (the centre
// of the two windows' overlap, t the frame's centre), which reached the reference at
// t - (d_a + d_b) / 2, while reference pair k describes the one that reached it at t - d_k / 2
// (measurement.h). For a moving source the cross pair's lag is therefore moved to those
// instants, d_ab + (r_b d_a - r_a d_b) / 2 with r_k pair k's delay rate: without it a source at
// 1 m/s past a 2.8-m tetrahedron in water left the fused delays 0.01 sample off (the pairs'
// scatter is 0.02), and its track drifted 2 m in range over 6 s at six apertures.
//
// A frame without cross pairs, or where no cross pair has a peak where predicted, is left
// exactly as it was. Cost: O(cross pairs x 17) for the peaks and O(P^3) for the solve,
// P = M - 1 <= 15: a few microseconds (the cross pairs' transforms are the caller's).
#pragma once

#include <span>
#include <vector>

#include "engine/core/measurement.h"

namespace localizer::engine {

struct FusionReport {
  int cross_edges = 0;             // cross pairs whose peak entered the solution
  int dropped_edges = 0;           // edges (reference or cross) dropped as outliers
  int fused_pairs = 0;             // reference pairs given fused delays
  double independent_share = 1.0;  // f below, after this frame
};

// Holds its scratch between frames (one per session; not thread-safe).
class PairFusion {
 public:
  static constexpr double kMinPeakSnr = 5.0;      // a reference pair below (unconfirmed) is not used
  static constexpr double kMinCrossPeak = 3.0;    // noise sds
  static constexpr double kOutlierSigmas = 4.0;   // an edge's residual beyond this is dropped
  static constexpr double kShareSmoothing = 0.2;  // per frame, for f (below)
  static constexpr int kMaxNodes = 15;            // reference pairs (16 sensors); more: not fused

  // Fuses `m` in place (above); m->cross_pairs as measured (none: nothing changes).
  // delay_rates (s/s, one per m->pairs, e.g. a track's predicted dTDOA/dt; empty: 0) put each
  // cross pair at the instants its reference pairs describe (below).
  FusionReport Fuse(Measurement* m, std::span<const double> delay_rates = {});

 private:
  struct Edge {
    int a = -1;      // node of the sensor subtracted (-1: the reference)
    int b = -1;      // node of the sensor added
    double d = 0.0;  // samples
    double w = 0.0;  // 1 / sigma^2, samples^-2
    bool kept = true;
  };
  std::vector<int> node_of_sensor_;
  std::vector<int> pair_of_node_;
  std::vector<Edge> edges_;
  std::vector<double> calibration_, lag_of_node_, sigma_of_node_, rate_of_node_;
  double independent_share_ = 1.0;
  int frames_ = 0;
};

}  // namespace localizer::engine
