#include "engine/pipeline/session_memory.h"

#include <algorithm>

namespace localizer::engine {
namespace {

// Measured on x86-64 (tests/pipeline/session_memory_test.cc, LOCALIZER_MEMORY_PROBE=1) and
// rounded up: bytes per unit of what grows.
// Measured 2026-12-01 (x86-64, glibc; tests/pipeline/session_memory_test.cc with
// LOCALIZER_MEMORY_PROBE=1) and given a margin of about 1.4: the particle filter held ~115
// bytes a particle, the multiple-model one ~585 (a cloud per motion model), an audio
// session ~42 bytes per channel per frame sample (frame, despiked copy, spectra, pair
// cross-spectra and GCC, FFT plans), a detection session ~4.8 KB a track with every gate
// saturated (64 gate pairs a track, with their sorted and greedy copies and the vectors'
// growth).
constexpr int64_t kAudioBaseBytes = int64_t{2} << 20;
constexpr int64_t kParticleBytes = 160;
constexpr int64_t kMultiModelParticleBytes = 896;
constexpr int64_t kChannelSampleBytes = 56;
constexpr int64_t kTrackBytes = 1024;   // a track, its report, its history
constexpr int64_t kEdgeBytes = 16 * 6;  // a gate pair: edges, sorted and greedy copies, x2 growth
constexpr int64_t kPlotBytes = 256;     // a converted plot and its grid cell

int64_t ParticleBytes(const AudioSessionConfig& config) {
  switch (config.tracker.kind) {
    case FilterKind::kPf:
      return kParticleBytes * config.tracker.particle.particles;
    case FilterKind::kMmpf:
      return kMultiModelParticleBytes * config.tracker.particle.particles;
    default:
      return 0;  // Kalman filters: a few 6 x 6 matrices
  }
}

}  // namespace

int64_t SessionMemoryBytes(const AudioSessionConfig& config) {
  const int64_t channels = static_cast<int64_t>(config.sensors_m.size());
  return kAudioBaseBytes + ParticleBytes(config) + kChannelSampleBytes * channels * std::max(config.frame_samples, 64);
}

int64_t SessionMemoryBytes(const DetectionSessionConfig& config) {
  const tws::TwsOptions& o = config.tws;
  const int64_t tracks = o.max_tracks;
  return (int64_t{1} << 20) + tracks * (kTrackBytes + kEdgeBytes * o.gate_search_budget) +
         kPlotBytes * o.max_plots_per_scan;
}

int64_t SessionMemoryBytes(const SessionConfig& config) {
  return std::visit([](const auto& c) { return SessionMemoryBytes(c); }, config);
}

int64_t LocateMemoryBytes(const AudioSessionConfig& config, int64_t samples_per_channel) {
  const int64_t channels = static_cast<int64_t>(config.sensors_m.size());
  // The decoded block (float), and the frame's transforms: a frame as long as the block.
  return kAudioBaseBytes + channels * samples_per_channel * (4 + kChannelSampleBytes);
}

}  // namespace localizer::engine
