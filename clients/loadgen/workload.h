// What the load generator's sessions send, made once and shared read-only by every session.
//
// The scene is loadtest.py's: a 1.5 m tetrahedron (plus a ring of sensors beyond 4
// channels), sound speed 1500 m/s, GCC band 200-8000 Hz (the upper edge at most 0.45 fs),
// one broadband source near (2.5, 1.5, -1.0) m moved to whole-sample TDOAs, 20 dB SNR. The
// recording lasts --signal-seconds (whole blocks) and is periodic in its length, so sessions
// loop it block after block with every delay intact across the wrap.
//
// Source: Gaussian white noise (std::mt19937_64 seeded with --seed) band-limited as
// loadtest.py does it, by zeroing the FFT bins outside the band (FFTW, engine/tdoa/fftw_util.h),
// scaled to a standard deviation of 0.1; channel k is the source delayed by its TDOA (circular
// shift) plus independent white noise 20 dB below. Same seed, same samples; not the same
// draws as loadtest.py's numpy generator, only the same signal in distribution.
//
// Every block is serialised once: a block request on the wire is
//   0x1a <length> 0x08 <sequence varint> <body k>
// (TrackRequest field 3 holding SampleBlock field 1, then the block's other fields), so
// sending block `sequence` writes a prefix of at most 17 bytes before the shared body.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "clients/loadgen/load_options.h"
#include "localizer/v1/localizer.pb.h"

namespace localizer::loadgen {

class Workload {
 public:
  // Cost: two FFTs of the recording's length and the copies (tens of ms for 4 s).
  explicit Workload(const LoadOptions& options);

  // The serialised TrackRequest{open} of session `index` (seed + index, label "loadgen-INDEX").
  std::string OpenRequest(int index) const;
  // How many distinct blocks the recording holds; block request k uses body k % count.
  int block_count() const { return static_cast<int>(bodies_.size()); }
  // The serialised SampleBlock of block k without its sequence (sequence 0 is not written).
  const std::string& body(int k) const { return bodies_[k]; }
  // Writes the prefix that turns body(k) into TrackRequest{block{sequence, ...}}: returns its
  // length (<= kMaxPrefixBytes).
  static constexpr int kMaxPrefixBytes = 1 + 10 + 1 + 10;
  static int BlockPrefix(uint64_t sequence, size_t body_bytes, char* out);

  const std::vector<double>& sensors_m() const { return sensors_m_; }  // x, y, z per sensor
  const std::vector<int>& tdoa_samples() const { return tdoa_samples_; }

 private:
  LoadOptions options_;
  std::vector<double> sensors_m_;
  std::vector<int> tdoa_samples_;  // arrival at sensor k minus at sensor 0, whole samples
  double band_high_hz_ = 0.0;
  std::vector<std::string> bodies_;
};

// loadtest.py's array: the tetrahedron of edge `edge_m` (alternate corners of a cube), then
// channels - 4 sensors on a ring of radius 0.6 edge, alternately 0.4 edge below and above.
std::vector<double> ArrayPositions(int channels, double edge_m);

}  // namespace localizer::loadgen
