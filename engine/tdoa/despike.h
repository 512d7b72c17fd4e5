// An impulsive-noise front end: per-frame, per-channel clipping at a robust scale, run on a
// caller's copy of each frame before the TDOA estimator.
//
// For each channel x of the frame (channel-major, `channels` x `samples` floats):
//     scale = 1.4826 * median |x|        (the MAD about zero; = the standard deviation for
//                                          zero-mean Gaussian samples; the median of at most
//                                          256 evenly spaced samples of the channel)
//     x <- clamp(x, -k scale, +k scale)   k = DespikeOptions::despike_k (0: off)
// The median comes from a branch-free bisection over |x| of at most 256 samples (to 1e-6 of
// the largest); a
// channel whose largest |x| is within the limit is left untouched after one pass; the frame
// is changed in place. An impulse on 1 % of the samples moves the median by about 1 %, so the clip level
// follows the background (source + noise), not the impulses. Nothing is kept between frames.
//
// Why it helps GCC-PHAT: an impulse of amplitude A adds a flat spectrum of level A to every bin
// of its channel; PHAT divides each bin by |X_k X_r*|, so a few impulses 30x the noise whiten
// the cross-spectrum into noise and the peak can land anywhere in the window (tens of ms off).
// Clipped at 5 sigma, the same impulses carry at most 0.25 % of the frame's power per 1 % of
// samples.
// What it leaves alone: a Gaussian background is clipped on 5.7e-7 of its samples at k = 5, so
// the GCC is unchanged to float rounding on ordinary frames. An impulsive *source* (clicks,
// coherent across channels) is clipped the same way on every channel: its waveform is distorted
// (harmonics) but identically delayed on each, so the delays stay right (tested).
//
// Measured (tests/tdoa/despike_test.cc, tetrahedron, 11025 Hz, 4096-sample frames, 200-4000 Hz
// source at 10 dB, band set, GCC-PHAT sinc, 30 frames x 3 pairs):
//   Gaussian noise only:           rms error 0.0087 sample without, 0.0087 with (unchanged)
//   + alpha-stable impulses (alpha 1.5, scale 30x the noise std, 1 % of samples, independent
//     per channel):                rms 3.0 samples without (6 % of pairs > 1 sample off, up to
//                                  tens of samples), 0.012 with (0 % off): ~250x smaller;
//                                  0.013 with the coincidence gate at 20 samples
//   click train (kClicks, 300-3000 Hz, 20 dB): worst pair error 0.025 sample unclipped, 0.25
//                                  clipped (each channel's clip level and sampling phase differ,
//                                  so clipping distorts the pulses a little differently),
//                                  0.025 with the coincidence gate at 20 samples
//   the same impulses, gate window 170 samples (a large array): 0.012 (the gate sees that
//                                  chance explains the coincidences and clips them all;
//                                  2.5 samples rms, 2 % of pairs off, before it compared)
// So set coincidence_samples (to the array's largest delay in samples plus a few) wherever
// the source may itself be impulsive; it costs the impulse scene nearly nothing. Where chance
// coincidences are common (a large array, dense impulses) a coherent click source is clipped
// like the impulses (0.25 sample above) rather than keeping the impulses with it.
// Cost (tests/bench/gcc_bench.cc, BM_Despike, 4 x 4096 frame): see BENCHMARKS / the bench;
// O(channels x samples): the median's bisection and one max pass per channel.
#pragma once

#include <vector>

#include "engine/core/status.h"

namespace localizer::engine {

struct DespikeOptions {
  double despike_k = 5.0;  // clip at k robust standard deviations; 0 = off; else in [1, 1e6]
  // 0: clip every outlier. > 0: keep an outlier that every other channel also has within
  // +-coincidence_samples (a coherent impulsive source, e.g. a click, reaches every sensor
  // within the array's largest delay). Set it to the array's largest delay in samples plus a
  // few. In [0, 1 << 20]. The gate is used on a channel only when most of its outliers line
  // up and more do than chance explains (three binomial sds above the share that independent
  // impulses at the other channels' outlier rates would give); otherwise they are all
  // clipped. Without that test a wide window kept nearly every impulse: 170 samples (15 m of
  // water at 16 kHz) lines up 1 % impulses on four channels by chance ~90 % of the time.
  int coincidence_samples = 0;

  // OK, or INVALID_ARGUMENT naming DespikeOptions.despike_k and its value.
  Status Validate() const;
};

struct DespikeStats {
  int clipped_samples = 0;  // over all channels
};

struct DespikeScratch {  // reused buffers; a caller that keeps one allocates nothing per frame
  std::vector<float> magnitudes;
  std::vector<int> outliers_before;  // per channel, prefix counts of outliers
  std::vector<float> limits;         // per channel, the clip level
};

// Clips frame[c * samples + i] in place as above. `scratch` may be null (then buffers are
// allocated per call).
// INVALID_ARGUMENT when frame is null, channels < 1, samples < 1 or options are invalid;
// the frame is then untouched. Non-finite samples are left to the estimator to reject (the
// median ignores nothing: a NaN channel's scale is unspecified but the call is safe).
Status Despike(const DespikeOptions& options, float* frame, int channels, int samples, DespikeScratch* scratch,
               DespikeStats* stats = nullptr);

// The same without touching `frame`: returns `frame` itself when no sample exceeds its
// channel's clip level (most frames: no copy), else *clipped, a copy of the frame clipped as
// Despike would (bit for bit). The pointer is valid until *clipped changes. INVALID_ARGUMENT
// as Despike, and when clipped is null.
StatusOr<const float*> DespikedFrame(const DespikeOptions& options, const float* frame, int channels, int samples,
                                     DespikeScratch* scratch, std::vector<float>* clipped,
                                     DespikeStats* stats = nullptr);

}  // namespace localizer::engine
