// How many samples a session's new frame adds to the stream its previous frame ended:
// GpuTdoaEstimator sends only those to its device ring (sample_ring.cuh).
//
// The estimator interface (engine::TdoaEstimator) hands over whole frames and no hop, and a
// frame is not always a plain slice of the stream (the session may despike it first), so the
// overlap is found from the data: the new frame's first F - s samples of every channel must
// equal, bit for bit, the previous frame's last F - s. Bit equality is what makes the frame
// read back from the ring identical to the frame given, whatever s is chosen: a wrong guess
// can only cost bus bytes, never change a result. (Bits, not ==: -0.0 == 0.0 and NaN != NaN.)
//
// Cost on the host: the hint (the last shift found: a framer's hop) is checked first, one
// memcmp over (F - s) samples per channel (~2 us for 4 x 2048). Without the hint, shifts are
// tried in increasing order, each pre-screened on two samples of channel 0, and at most
// kMaxFullCompares of them compared in full, so a pathological stream (a constant signal
// that changes only at the end) costs a bounded few passes and falls back to the whole
// frame.
#pragma once

#include <cstring>

namespace localizer::gpu {

inline constexpr int kMaxFullCompares = 4;

namespace overlap_detail {

// Whether frame's first F - s samples equal previous's last F - s, bitwise, in every channel.
inline bool OverlapsBy(const float* previous, const float* frame, int channels, int frame_samples, int shift) {
  const std::size_t kept = static_cast<std::size_t>(frame_samples - shift);
  for (int c = 0; c < channels; ++c) {
    const float* row_prev = previous + static_cast<std::size_t>(c) * frame_samples + shift;
    const float* row_new = frame + static_cast<std::size_t>(c) * frame_samples;
    if (std::memcmp(row_prev, row_new, kept * sizeof(float)) != 0) return false;
  }
  return true;
}

inline bool SameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

}  // namespace overlap_detail

// The number of samples at the end of each channel of `frame` that are new: the smallest
// shift s in [1, F - 1] found with frame[c][0, F - s) == previous[c][s, F) for every channel
// (the hint first, when it is in range and fits), else F (nothing reusable found). Both
// frames are channel-major, `channels` rows of F = frame_samples.
inline int NewSampleCount(const float* previous, const float* frame, int channels, int frame_samples, int hint) {
  using overlap_detail::OverlapsBy;
  using overlap_detail::SameBits;
  if (hint >= 1 && hint < frame_samples && OverlapsBy(previous, frame, channels, frame_samples, hint)) return hint;
  int full_compares = 0;
  const int middle = frame_samples / 2;
  for (int s = 1; s < frame_samples && full_compares < kMaxFullCompares; ++s) {
    if (s == hint) continue;  // already refuted
    if (!SameBits(frame[0], previous[s])) continue;
    const int probe = middle < frame_samples - s ? middle : frame_samples - s - 1;
    if (!SameBits(frame[probe], previous[s + probe])) continue;
    ++full_compares;
    if (OverlapsBy(previous, frame, channels, frame_samples, s)) return s;
  }
  return frame_samples;
}

}  // namespace localizer::gpu
