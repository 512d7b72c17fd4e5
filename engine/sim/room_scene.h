// A scene in a shoebox room, for rehearsing an array before a recording (issue 18's
// `localizer-cli simulate --room`): fixed sources in a room (room.h, image-source method),
// each emitting band-limited noise, tones over noise, or speech-like bursts, rendered to every
// sensor, plus white sensor noise.
//
// Signals, each of unit power at level_db 0 and scaled by 10^(level_db / 20):
//   broadband  white Gaussian noise through DesignBandPassFir(band) (band_pass_fir.h);
//   tones      3 tones at frequencies uniform in the middle 80 % of the band carrying 80 %
//              of the power, over the broadband noise carrying 20 %;
//   bursts     the broadband noise, on for a duration uniform in [on_min_s, on_max_s], off
//              for one uniform in [off_min_s, off_max_s], alternately from a random phase,
//              with 10 ms raised-cosine edges: talkers with pauses.
//   speech     a speech-like talker (speech_like.h: harmonic voiced and noisy unvoiced
//              syllables, most power below 1 kHz), gated on and off like bursts.
// Every source sounds only within [start_s, stop_s) of emission time. Sensor noise: white,
// of power noise_db relative to a level-0 source's direct sound at 1 m (1 / (4 pi)^2).
// Draws come from one std::mt19937_64 per source and one for the noise, seeded from `seed`
// and the index: a scene and a seed give bit-identical samples.
//
// Cost: room.h's (the image lattice up to RT60, one FFT convolution per source and
// sensor) plus the band-pass filtering; bounded by Validate's limits.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/sim/room.h"

namespace localizer::engine {

enum class RoomSignal { kBroadband, kTones, kBursts, kSpeech };
// "broadband" | "tones" | "bursts" | "speech"; INVALID_ARGUMENT naming `field` otherwise.
StatusOr<RoomSignal> ParseRoomSignal(const std::string& name, const std::string& field);
const char* RoomSignalName(RoomSignal signal);

struct RoomSceneSource {
  Vec3 position_m = Vec3::Zero();  // inside the room
  RoomSignal signal = RoomSignal::kBursts;
  double band_low_hz = 100.0;  // 0 <= low < high <= fs / 2
  double band_high_hz = 7000.0;
  double level_db = 0.0;                  // in [-60, 60]
  double on_min_s = 0.4, on_max_s = 1.5;  // bursts and speech: 0 < min <= max
  double off_min_s = 0.2, off_max_s = 1.0;
  double start_s = 0.0;  // sounds within [start_s, stop_s) of emission time
  double stop_s = std::numeric_limits<double>::infinity();
};

struct RoomScene {
  ShoeboxRoom room;
  double sample_rate_hz = 16000.0;       // in [1000, 192000]
  double duration_s = 10.0;              // in (0, 600]
  double noise_db = -20.0;               // in [-120, 40]
  std::vector<RoomSceneSource> sources;  // 1 to 16

  // INVALID_ARGUMENT naming the field (sources[1].band_hz, room.rt60_s, ...): values out of
  // range, a source or sensor outside the room, or more than 2e8 samples over all sensors.
  Status Validate(const std::vector<Vec3>& sensors_m) const;
};

// When each source sounds: [on_s, off_s) in emission time (bursts give many intervals).
struct SoundingInterval {
  int source = 0;
  double on_s = 0.0;
  double off_s = 0.0;
};

struct RenderedRoomScene {
  int64_t samples_per_channel = 0;
  std::vector<float> samples;              // sensors x samples_per_channel, channel-major
  std::vector<SoundingInterval> sounding;  // by source, then time
};

StatusOr<RenderedRoomScene> RenderRoomScene(const RoomScene& scene, const std::vector<Vec3>& sensors_m, uint64_t seed);

}  // namespace localizer::engine
