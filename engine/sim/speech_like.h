// A speech-like talker for room scenes (room_scene.h's "speech" signal): not speech, but the
// three things about speech that a direction finder meets and white bursts lack.
//   - Sparse spectra. Voiced syllables are a harmonic series on the talker's fundamental (one
//     f0 per talker, drawn in [90, 250] Hz; within a syllable it glides by up to +-15 %), with
//     a -6 dB per octave tilt and three formant resonances drawn per syllable (F1 300-800 Hz,
//     F2 900-2300 Hz, F3 2300-3200 Hz, bandwidths 100-250 Hz). Most of the power lies below
//     1 kHz, where a small board resolves directions worst.
//   - Unvoiced syllables: noise in the upper part of the band (from max(low, 0.3 x high) to
//     high), like fricatives.
//   - Syllabic rhythm: syllables of 0.12-0.25 s, 70 % voiced, each at its own level (+-6 dB),
//     separated by 20-80 ms of silence, with 10 ms raised-cosine edges.
// Only components within [band_low_hz, band_high_hz] are made, and harmonics only up to
// 8 kHz. The result has unit mean power over all n samples (gaps included), so a room scene's
// level_db means the same as for the other signals; the scene's on/off gate (utterances and
// pauses) is applied by the caller.
// Deterministic for a given generator state. Cost: O(n x harmonics below min(band_high_hz,
// 8 kHz) / f0), at most about 100 cosines per sample; about 0.3 s per source for 20 s at 16 kHz.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

namespace localizer::engine {

std::vector<double> SpeechLikeSignal(double band_low_hz, double band_high_hz, double sample_rate_hz, int64_t n,
                                     std::mt19937_64* rng);

}  // namespace localizer::engine
