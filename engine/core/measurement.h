// What the TDOA front end hands the tracker for one frame.
#pragma once

#include <vector>

namespace localizer::engine {

// One local extremum of a pair's GCC: a delay the pair's channels share (a path, an echo, an
// image of the source) or a noise peak. See gcc_phat.h for how candidates are picked.
struct DelayCandidate {
  double delay_s = 0.0;        // refined like the main peak
  double value = 0.0;          // GCC at the integer extremum; negative: an inverted copy
  double delay_sigma_s = 0.0;  // standard deviation of delay_s, as delay_sigma_s below
};

// One sensor pair (reference, sensor). Sign convention throughout the engine:
//   delay_s = t_arrival(sensor) - t_arrival(reference) = (|s - m_sensor| - |s - m_ref|) / c,
// so a positive delay means the source is nearer the reference.
struct PairMeasurement {
  int sensor = 0;           // index of the non-reference sensor
  double delay_s = 0.0;     // TDOA at the interpolated GCC peak
  double quality = 0.0;     // peak over the largest sidelobe outside the main lobe (small,
                            // even < 1, means no clear peak; see gcc_phat.h)
  double peak_value = 0.0;  // GCC value at the peak (PHAT: 1 for a perfect single path)
  // peak_value over the GCC's standard deviation when the channels hold only independent
  // noise (1 / sqrt(in-band bins of the full spectrum) for PHAT; for learnt weights, the same
  // with the weights' effective bin count (sum w)^2 / sum w^2): the detection
  // statistic. Noise alone gives ~2-4 (max over the window); a source far more.
  double peak_snr = 0.0;
  // Standard deviation of delay_s on this frame, seconds, from the GCC's own curvature and
  // the spread of its cross-spectrum about the measured delay (gcc_phat.h derives it and
  // states how well it agrees with the measured spread). It describes the scatter about the
  // peak that was found; whether that peak is the source is peak_snr's and quality's job.
  // Both front ends (CPU and GPU) fill it; 0 would mean not computed, and filters would
  // then fall back on the GCC window's curvature, which tracks far worse (tetra-air: 0.12 m
  // pooled RMSE with it, 3.5 m without).
  double delay_sigma_s = 0.0;
  // Set by a session that found this pair's peak where its established track predicts it
  // (within the association gate): the filters then use the pair down to a lower peak SNR
  // (pair_noise.h), since a peak in a few predicted lags is far less likely noise than the
  // largest value anywhere in the window.
  bool confirmed = false;
  // The K largest local extrema of |GCC| in the lag window, at least one envelope width
  // apart (K = GccOptions::max_candidates). candidates[0] is the main peak (delay_s,
  // peak_value, delay_sigma_s); the others follow by decreasing |value|. Empty when the
  // frame had no energy in the band.
  std::vector<DelayCandidate> candidates;
  // The GCC function over the searched lag window, at integer lags
  // first_lag_samples, first_lag_samples + 1, ...; lag in samples = delay_s * sample_rate_hz.
  // Trackers read it at a candidate's predicted lag (GCC likelihood).
  int first_lag_samples = 0;
  std::vector<float> gcc;
};

// The GCC of two sensors that are both not the reference (sensor_a < sensor_b), measured
// only for redundancy (GccOptions::cross_pairs_max_sensors): on a 4-sensor array the three
// reference pairs always have an exact solution, also with one pair on an echo or a noise
// peak, and only the pairs without the reference can outvote it. Acquisition and presence
// read it (lag_field.h); the filters do not. Lag l (samples) of gcc stands for
// t_arrival(sensor_b) - t_arrival(sensor_a) = l / sample_rate_hz, lags first_lag_samples,
// first_lag_samples + 1, ..., normalised as PairMeasurement::gcc.
struct CrossPairGcc {
  int sensor_a = 0;
  int sensor_b = 0;
  // 1 / the GCC's noise-only standard deviation (as peak_snr / peak_value of a reference
  // pair); 0 when the frame had no energy in the band.
  double noise_floor_inverse = 0.0;
  int first_lag_samples = 0;
  std::vector<float> gcc;
  // The K lags on either side of the window, normalised as gcc (K = size / 2; the CPU front end's
  // kPeakHalfWidth, 8): the K below first_lag_samples, then the K above the window's last lag,
  // so a peak near the window's end can be refined like one inside (pair_fusion.h).
  std::vector<float> gcc_beyond;
};

struct Measurement {
  // Reception instant, in seconds from the first sample at the receivers, of the centre of
  // the frame the pairs were measured on. Pair k describes the emission that reached the
  // reference at t_s - delay_s / 2 (the centre of the overlap of the two windows).
  double t_s = 0.0;
  double sample_rate_hz = 0.0;
  // The variance of time about the frame's centre under the weight the pairs' cross-power
  // gives each instant (the product of the two channels' tapers), s^2: T^2 / 12 for a
  // rectangular frame of T seconds, 0.02 T^2 for Hann. A pair whose delay changes at rate r
  // (s/s) within the frame spreads its GCC peak over a spread of variance r^2 times this.
  // 0: not stated (a front end that does not fill it).
  double window_time_var_s2 = 0.0;
  std::vector<PairMeasurement> pairs;  // one per non-reference sensor, ascending sensor index
  // Every pair of non-reference sensors (a < b, ascending a then b) once the front end was
  // asked for them (TdoaEstimator::MeasureCrossPairs); empty otherwise (not asked, the GPU
  // front end, larger arrays, keep_gcc off).
  std::vector<CrossPairGcc> cross_pairs;
};

}  // namespace localizer::engine
