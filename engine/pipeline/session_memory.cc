#include "engine/pipeline/session_memory.h"

#include <algorithm>
#include <cmath>

#include "engine/doa/array_shape.h"
#include "engine/pipeline/session.h"

namespace localizer::engine {
namespace {

// Measured on x86-64 (tests/pipeline/session_memory_test.cc, LOCALIZER_MEMORY_PROBE=1) and
// rounded up: bytes per unit of what grows.
// Measured 2026-12-01 (x86-64, glibc; tests/pipeline/session_memory_test.cc with
// LOCALIZER_MEMORY_PROBE=1) and given a margin of about 1.4: the particle filter held ~115
// bytes a particle, the multiple-model one ~585 (a cloud per motion model), an audio
// session ~42 bytes per channel per frame sample (frame, despiked copy, spectra, pair
// cross-spectra and GCC, FFT plans; since, about 12 bytes per frame sample more for a
// channel read along its delay rate and the plain spectrum kept meanwhile, delay_warp.h),
// a detection session ~4.8 KB a track with every gate
// saturated (64 gate pairs a track, with their sorted and greedy copies and the vectors'
// growth).
constexpr int64_t kAudioBaseBytes = int64_t{2} << 20;
constexpr int64_t kParticleBytes = 160;
constexpr int64_t kMultiModelParticleBytes = 896;
constexpr int64_t kChannelSampleBytes = 56;
constexpr int64_t kTrackBytes = 1024;          // a track, its report, its history
constexpr int64_t kEdgeBytes = 16 * 6;         // a gate pair: edges, sorted and greedy copies, x2 growth
constexpr int64_t kPlotBytes = 256;            // a converted plot and its grid cell
constexpr int64_t kPairBinBytes = 16 * 3 / 2;  // a pair's complex double per bin, with a margin
constexpr int64_t kPairLagBytes = 64;          // a pair's lag-field entry (GCC float, field double, ...)

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

// A direction session (direction_stage.h): every pair's cross-spectrum (complex doubles over
// up to half the transform) in the current frame and in the ring of earlier frames its
// rises look back on (frame / hop of them), each pair's lag field, the channels' transforms.
// Pairs grow with the square of the sensors: 64 sensors are 2016 pairs. Positions (a planar
// or linear array asked for them) keep a second copy of the lag fields (SrpPhat::whole_field).
int64_t DirectionSessionBytes(const AudioSessionConfig& config, bool positions) {
  const auto sensors = static_cast<int64_t>(config.sensors_m.size());
  const int64_t pairs = sensors * (sensors - 1) / 2;
  const auto shape = ClassifyArray(config.sensors_m);
  const double aperture_m = shape.ok() ? shape->aperture_m : 0.0;
  const int64_t frame = std::max(config.frame_samples, 64);
  const auto max_lag =
      static_cast<int64_t>(std::ceil(aperture_m / std::max(config.sound_speed_mps, 1e-9) * config.sample_rate_hz)) + 3;
  const int64_t transform = (frame + max_lag + 1) * 5 / 4;  // NextFastFftSize rounds up by less
  const int64_t rise_frames = (frame + std::max(config.hop_samples, 1) - 1) / std::max(config.hop_samples, 1);
  const int64_t spectra = kPairBinBytes * pairs * (transform / 2) * (rise_frames + 2);
  const int64_t fields = kPairLagBytes * pairs * (2 * max_lag + 1) * (positions ? 2 : 1);
  return kAudioBaseBytes + spectra + fields + kChannelSampleBytes * sensors * transform;
}

int64_t SessionMemoryBytes(const AudioSessionConfig& config) {
  const int64_t channels = static_cast<int64_t>(config.sensors_m.size());
  const auto sources = ReportsSources(config);
  if (sources.ok() && *sources) {
    const auto localization = ResolveLocalization(config);
    return DirectionSessionBytes(config, localization.ok() && *localization == Localization::kPosition);
  }
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
