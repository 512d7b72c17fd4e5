// Each frequency bin's share of signal in one frame: 1 - c N / P, where P is the bin's power
// (summed over the channels, averaged over a few neighbouring bins) and N the frame's noise
// floor, a low quantile of the power averaged over a wider window. A bin holding only noise
// gets ~0, one holding a source far above the floor ~1. A frame whose spectrum is flat (its
// upper quantile within flat_spread of the floor: white sources, or noise alone) has no floor
// to read, and every share is 1.
//
// Used to weigh bins by their signal (engine/doa/pair_spectra.h, "Signal weighting"; GCC's
// kPhatShare, gcc_phat.h) and by the direction search's delay removal (the model of what a
// found source put in each bin). O(bins) per frame plus two nth_element over the bins; no
// allocation after the first frame of a size.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace localizer::engine {

struct SignalShareOptions {
  // The floor's window: the 10th percentile of a mean of 8 exponential bins is about 0.6 of
  // the mean, so noise_over_floor 1.7 gives noise-only bins ~0 rather than 0.4.
  std::size_t floor_window_bins = 8;
  // The window each bin's own power is averaged over (its share's P). A talker's harmonics
  // lie 3-8 bins apart at 31 Hz per bin (512 samples at 16 kHz): 3 keeps them apart.
  std::size_t share_window_bins = 3;
  double floor_quantile = 0.1;
  double noise_over_floor = 1.7;
  double flat_spread = 4.0;
  // The flatness test reads the true upper quantile (a second partition) when true; when
  // false, the element the floor's partition left at that rank (some bin above the floor,
  // seldom the quantile itself): the direction search's removal was tuned with it.
  bool exact_upper_quantile = true;
  // When > 0, the flatness test also reads the frame's largest floor-window average: a frame
  // whose upper quantile is within flat_spread is still not flat when that maximum reaches
  // flat_max_spread x floor. A source in under a tenth of the bins (a 300-3000 Hz talker at
  // 48 kHz holds 11 %) leaves the upper quantile on noise, and the frame would be weighed as
  // if nothing stood out.
  double flat_max_spread = 0.0;
};

// Options read from the noise's own statistics: `channels` independent channels' power
// summed and averaged over floor_window_bins + 1 bins is Gamma(k = channels x bins) about its
// mean. Its 10th and 90th percentiles (Wilson-Hilferty) set noise_over_floor (a bin starts to
// count at 1.35 times the noise's mean) and flat_spread (1.6 times noise's own 90/10 ratio);
// flat_max_spread is 1.6 times the ratio of noise's largest window average to its 10th
// percentile, the largest taken at z = 3.72 (1 % of frames over ~100 independent windows) with
// the bins of a transform zero-padded to twice the frame counted as half as many (they
// correlate in pairs). A frame stands out when either test says so.
// For the GCC's long frames (kPhatShare), where a 9-bin floor would leave a source a few dB
// over the noise flat: with 33 bins and 4 channels the factor is 1.52, flat_spread 2.0 and
// flat_max_spread 2.9 (white noise's largest 33-bin average over its floor, measured in numpy
// for 4 channels padded twice, 300 frames: 99th percentile 2.0 with a 0.2 taper, 2.4 with
// Hann; ACCURACY.md, "Thirty-first pass"; tests/tdoa/phat_share_test.cc asserts noise flat and
// a narrow source seen).
SignalShareOptions SignalShareOptionsForNoise(int channels, std::size_t floor_window_bins);

class SignalShare {
 public:
  explicit SignalShare(const SignalShareOptions& options = {}) : options_(options) {}

  // Finds the shares of `power` (one value per bin, >= 0). Returns whether the frame is flat
  // (then every share is 1). An empty span gives no shares and a flat frame.
  bool Find(std::span<const double> power);

  // This frame's shares, one per bin, in [0, 1].
  std::span<const double> shares() const { return share_; }
  bool flat() const { return flat_; }

 private:
  // Each value of power averaged over `window` bins centred on it (clipped at the ends).
  void Smooth(std::span<const double> power, std::size_t window, std::vector<double>* out) const;

  SignalShareOptions options_;
  std::vector<double> smoothed_, sorted_, share_;
  bool flat_ = true;
};

}  // namespace localizer::engine
