// Whether one heard direction is a room's reflection of another: beams steered at the two
// directions, and the correlation of the second with the first delayed.
//
// Why. A reflection is a coherent copy of its source from another direction: it passes the
// noise threshold frame after frame while its source sounds, and on an array that resolves it
// (a line array maps every image source to a cone angle of its own) it can hold a quarter of
// its frames' strongest peaks, where the tracker's rules (direction_tracker.h: onsets, leading)
// expect a reflection to lead almost never. Measured on seeded rooms through the CLI (line of
// 8 microphones over 28 cm, one talker at 3 m, RT60 0.24 s): the ceiling's image, 2 ms behind the
// talker at a cone angle 20 degrees away, held 0.3-1.0 of the direct peak's statistic and led 22 %
// of the frames its track heard, 28 s of false source per minute; over the draw, 95 % of the
// false rows fell while a talker sounded. What tells a reflection from a second talker is its
// signal: the image's is the talker's own, delayed by the image's extra path. Two talkers'
// signals do not correlate at any lag.
//
// How. Each sensor's frame is transformed once (zero padded to M >= N + L, L the longest extra
// path searched, so that the correlation does not wrap), and for two directions u_i, u_j the
// delay-and-sum beams B(k) = sum_m X_m(k) exp(i w_k t_m(u)) (t_m the plane wave's arrival at
// sensor m relative to the centroid) are formed over the bins where they are selective: the
// leakage |(1/S) sum_m exp(i w_k (t_m(u_i) - t_m(u_j)))| of each beam towards the other's
// direction is below max_leakage (a small array's beams pass everything at low frequencies,
// and there each holds the other's source as much as its own). The correlation coefficient of
// the two beams at lag tau,
//     rho(tau) = Re sum_k B_i(k) conj(B_j(k)) exp(i w_k tau) / sqrt(sum_k |B_i|^2 sum_k |B_j|^2),
// is at most 1; B_j = g B_i delayed by D gives rho(-D) = |g| sqrt(P_i / P_j) (j lags i: `lagging`
// holds rho(-tau), tau = 1..L, `leading` rho(+tau)). Lags below the beams' own spread
// (max_m |t_m(u_i) - t_m(u_j)| + 2 samples), where each beam's leak of the other's source
// lands, are not searched (min_lag).
//
// Measured on that room (a throwaway numpy model of this test, frames where the talker sounds):
// the ceiling image gives rho(-62 samples) 0.26 in the median frame (0.20-0.33, p10-p90); two
// talkers 83 degrees apart in another room of the draw give 0.06 (0.02-0.11) at the lag where
// the second's beam holds the first's wall reflection. A single frame's largest rho over 250 lags
// is 0.14-0.25 by chance, so the evidence is averaged over frames (EchoWatch, echo_watch.h).
//
// Cost per frame it is used: ceil(S / 2) complex transforms of M points (two channels in one,
// engine/tdoa/packed_transforms.h), and per pair of directions 2 S products over the selective
// bins and one inverse transform. Not thread-safe.
#pragma once

#include <vector>

#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/tdoa/fftw_util.h"
#include "engine/tdoa/packed_transforms.h"

namespace localizer::engine {

struct EchoTestOptions {
  // The longest frame tested: every sensor's spectrum is kept (at most 2^17 + 16 floats,
  // about 512 KiB, per sensor).
  static constexpr int kMaxFrameSamples = 65536;
  double sample_rate_hz = 16000.0;
  double sound_speed_mps = 343.0;
  int frame_samples = 512;
  double band_low_hz = 0.0;
  double band_high_hz = 0.0;  // 0: the Nyquist frequency
  // The longest extra path searched, as a delay (s, > 0); at most frame_samples / 2 samples
  // are searched (a longer delay leaves too little of the frame to overlap).
  double max_delay_s = 0.012;
  double max_leakage = 0.5;  // in (0, 1): a bin is used where each beam passes at most this of the other
  // Fewer selective bins than this share of the band: the directions are not told apart (no test).
  double min_selective_share = 0.2;

  Status Validate() const;
};

struct EchoEvidence {
  int min_lag = 1;              // lags below are not searched (lagging/leading hold 0 there)
  std::vector<double> lagging;  // [tau - 1]: rho at -tau samples (beam j behind beam i), tau = 1..L
  std::vector<double> leading;  // [tau - 1]: rho at +tau samples (beam i behind beam j)
  double power_i = 0.0;         // sum over the selective bins of |B_i|^2
  double power_j = 0.0;
  // The same over kEchoSubBands consecutive quarters of the selective bins (for the beams'
  // envelopes, echo_watch.h).
  static constexpr int kSubBands = 4;
  double band_power_i[kSubBands] = {};
  double band_power_j[kSubBands] = {};
};

class EchoTest {
 public:
  // INVALID_ARGUMENT naming the option, or for fewer than 2 sensors.
  static StatusOr<EchoTest> Create(const std::vector<Vec3>& sensors_m, const EchoTestOptions& options);

  int max_lag() const { return max_lag_; }  // L, samples

  // The frame (sensors x frame_samples floats, channel-major): every sensor's spectrum.
  void Load(const float* frame);
  // The evidence that u_j is a reflection of u_i (unit directions from the array; for a linear
  // array any direction at the cone angle), from the last loaded frame. False (out untouched)
  // when too few bins tell the two directions apart.
  bool Compare(const Vec3& u_i, const Vec3& u_j, EchoEvidence* out);

 private:
  EchoTest() = default;
  EchoTestOptions options_;
  std::vector<Vec3> sensors_m_;  // relative to the centroid
  int fft_size_ = 0;
  int max_lag_ = 0;
  int first_bin_ = 0, end_bin_ = 0;  // in-band bins [first, end)
  FftwFloats spectra_, cross_;
  PackedTransforms packed_;                // two channels per forward transform; the correlation's inverse
  int spectrum_stride_ = 0;                // floats per sensor's spectrum
  std::vector<double> delay_i_, delay_j_;  // per sensor, samples
  std::vector<double> phasors_;            // Compare's scratch: steering phasors and rotations
  std::vector<double> band_i_, band_j_;    // ... the beams' powers in each selective bin
};

}  // namespace localizer::engine
