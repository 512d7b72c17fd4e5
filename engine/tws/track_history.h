// A track's scan-by-scan record, and the M-of-N rule read from it.
//
// TrackHistory::Record(hit) is called once per scan for every track, after association:
// bit 0 of `bits` is the latest scan (1: a measurement updated the track), bit k the scan k
// before; `age` counts the scans since initiation (the initiating one, or two for two-point
// initiation, included), `hits` the updates over its life, `misses` the scans in a row
// without one. `confirmed` is set by the initiator (initiator.h) and never cleared.
//
// MofN: "M hits in the last N scans", N <= 32 (one bit per scan). A tentative track is
// confirmed when it has M hits among its last N scans; it can no longer be confirmed when
// the hits it has in the window plus the scans left before its N-th (max(0, N - age)) fall
// short of M. Both questions cost a popcount.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>

namespace localizer::engine::tws {

struct TrackHistory {
  uint32_t bits = 0;  // bit k: the scan k before the latest brought a measurement
  int age = 0;        // scans since initiation, the initiating one(s) counting
  int hits = 0;
  int misses = 0;  // in a row
  bool confirmed = false;

  void Record(bool hit) {
    bits <<= 1;
    ++age;
    if (hit) {
      bits |= 1u;
      ++hits;
      misses = 0;
    } else {
      ++misses;
    }
  }
};

// M of the last N scans; 1 <= M <= N <= 32 (TwsOptions::Validate checks it).
class MofN {
 public:
  MofN(int m, int n) : m_(m), n_(n), mask_(n >= 32 ? 0xffffffffu : (1u << n) - 1u) {}

  int m() const { return m_; }
  int n() const { return n_; }
  int HitsInWindow(const TrackHistory& h) const { return std::popcount(h.bits & mask_); }
  bool Reached(const TrackHistory& h) const { return HitsInWindow(h) >= m_; }
  // Not even a hit on every scan left in the window would reach M.
  bool Unreachable(const TrackHistory& h) const { return HitsInWindow(h) + std::max(0, n_ - h.age) < m_; }

 private:
  int m_;
  int n_;
  uint32_t mask_;
};

}  // namespace localizer::engine::tws
