#include "engine/sim/room_scene.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "engine/sim/band_pass_fir.h"
#include "engine/sim/speech_like.h"

namespace localizer::engine {
namespace {

constexpr double kEdge_s = 0.01;          // bursts' raised-cosine edges
constexpr double kMaxTotalSamples = 2e8;  // sensors x samples
constexpr int kTones = 3;
constexpr double kTonePower = 0.8;

std::string Field(size_t i, const std::string& name) { return "sources[" + std::to_string(i) + "]." + name; }

}  // namespace

StatusOr<RoomSignal> ParseRoomSignal(const std::string& name, const std::string& field) {
  if (name == "broadband") return RoomSignal::kBroadband;
  if (name == "tones") return RoomSignal::kTones;
  if (name == "bursts") return RoomSignal::kBursts;
  if (name == "speech") return RoomSignal::kSpeech;
  return InvalidArgument(field + " is \"" + name + "\"; expected broadband, tones, bursts or speech");
}

const char* RoomSignalName(RoomSignal signal) {
  switch (signal) {
    case RoomSignal::kBroadband:
      return "broadband";
    case RoomSignal::kTones:
      return "tones";
    case RoomSignal::kBursts:
      return "bursts";
    case RoomSignal::kSpeech:
      return "speech";
  }
  return "broadband";
}

Status RoomScene::Validate(const std::vector<Vec3>& sensors_m) const {
  if (const Status s = room.Validate(); !s.ok()) return s;
  if (!(sample_rate_hz >= 1000.0 && sample_rate_hz <= 192000.0)) {
    return InvalidArgument("sample_rate_hz must be in [1000, 192000], got " + std::to_string(sample_rate_hz));
  }
  if (!(duration_s > 0.0 && duration_s <= 600.0)) {
    return InvalidArgument("duration_s must be in (0, 600], got " + std::to_string(duration_s));
  }
  if (!(noise_db >= -120.0 && noise_db <= 40.0)) {
    return InvalidArgument("noise_db must be in [-120, 40], got " + std::to_string(noise_db));
  }
  if (sources.empty() || sources.size() > 16) {
    return InvalidArgument("sources must list 1 to 16 sources, got " + std::to_string(sources.size()));
  }
  if (sensors_m.empty()) return InvalidArgument("the array has no sensors");
  if (static_cast<double>(sensors_m.size()) * duration_s * sample_rate_hz > kMaxTotalSamples) {
    return InvalidArgument("sensors x duration_s x sample_rate_hz exceeds 2e8 samples: shorten the scene");
  }
  const auto inside = [this](const Vec3& p) {
    return p.allFinite() && (p.array() > 0.0).all() && (p.array() < room.size_m.array()).all();
  };
  for (size_t m = 0; m < sensors_m.size(); ++m) {
    if (!inside(sensors_m[m])) {
      return InvalidArgument("sensor " + std::to_string(m) +
                             " lies outside the room (array_position_m + the array's "
                             "sensors_m must be inside room.size_m)");
    }
  }
  for (size_t i = 0; i < sources.size(); ++i) {
    const RoomSceneSource& s = sources[i];
    if (!inside(s.position_m)) return InvalidArgument(Field(i, "position_m") + " lies outside the room");
    if (!(s.band_low_hz >= 0.0 && s.band_low_hz < s.band_high_hz && s.band_high_hz <= 0.5 * sample_rate_hz)) {
      return InvalidArgument(Field(i, "band_hz") + " must satisfy 0 <= low < high <= sample_rate_hz / 2");
    }
    if (!(s.level_db >= -60.0 && s.level_db <= 60.0))
      return InvalidArgument(Field(i, "level_db") + " must be in [-60, 60]");
    if (!(s.on_min_s > 0.0 && s.on_min_s <= s.on_max_s && std::isfinite(s.on_max_s))) {
      return InvalidArgument(Field(i, "on_s") + " must be [min, max] with 0 < min <= max, finite");
    }
    if (!(s.off_min_s > 0.0 && s.off_min_s <= s.off_max_s && std::isfinite(s.off_max_s))) {
      return InvalidArgument(Field(i, "off_s") + " must be [min, max] with 0 < min <= max, finite");
    }
    if (!(s.start_s >= 0.0 && s.start_s < s.stop_s)) {
      return InvalidArgument(Field(i, "start_s") + " must be >= 0 and below stop_s");
    }
  }
  return Status::Ok();
}

StatusOr<RenderedRoomScene> RenderRoomScene(const RoomScene& scene, const std::vector<Vec3>& sensors_m, uint64_t seed) {
  LOCALIZER_RETURN_IF_ERROR(scene.Validate(sensors_m));
  const double fs = scene.sample_rate_hz;
  const auto n = static_cast<int64_t>(std::llround(scene.duration_s * fs));
  RenderedRoomScene out;
  out.samples_per_channel = n;
  std::vector<RoomSource> sources;
  for (size_t i = 0; i < scene.sources.size(); ++i) {
    const RoomSceneSource& s = scene.sources[i];
    std::seed_seq seq{seed, uint64_t{i}, uint64_t{0x524f4f4d}};  // "ROOM"
    std::mt19937_64 rng(seq);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::vector<double> signal = s.signal == RoomSignal::kSpeech
                                     ? SpeechLikeSignal(s.band_low_hz, s.band_high_hz, fs, n, &rng)
                                     : UnitPowerBandNoise(s.band_low_hz, s.band_high_hz, fs, n, &rng);
    if (s.signal == RoomSignal::kTones) {
      for (double& v : signal) v *= std::sqrt(1.0 - kTonePower);
      const double lo = s.band_low_hz + 0.1 * (s.band_high_hz - s.band_low_hz);
      const double width = 0.8 * (s.band_high_hz - s.band_low_hz);
      for (int k = 0; k < kTones; ++k) {
        const double f = lo + width * uniform(rng), phase = 2.0 * std::numbers::pi * uniform(rng);
        const double amplitude = std::sqrt(2.0 * kTonePower / kTones);
        for (int64_t t = 0; t < n; ++t) {
          signal[static_cast<size_t>(t)] +=
              amplitude * std::cos(2.0 * std::numbers::pi * f * static_cast<double>(t) / fs + phase);
        }
      }
    }
    // The gate: 1 while sounding (bursts alternate on and off), edges raised-cosine.
    std::vector<std::pair<double, double>> on;
    if (s.signal == RoomSignal::kBursts || s.signal == RoomSignal::kSpeech) {
      const auto draw = [&](double a, double b) { return a + (b - a) * uniform(rng); };
      double t = s.start_s - draw(0.0, s.off_max_s);  // a random phase: may start mid-burst
      while (t < std::min(s.stop_s, scene.duration_s)) {
        const double end = t + draw(s.on_min_s, s.on_max_s);
        on.emplace_back(std::max(t, s.start_s), std::min(end, s.stop_s));
        t = end + draw(s.off_min_s, s.off_max_s);
      }
    } else {
      on.emplace_back(s.start_s, s.stop_s);
    }
    std::vector<double> gate(static_cast<size_t>(n), 0.0);
    for (const auto& [a, b] : on) {
      const double b_s = std::min(b, scene.duration_s);
      if (!(b_s > a)) continue;
      out.sounding.push_back({static_cast<int>(i), a, b_s});
      const double edge = std::min(kEdge_s, 0.5 * (b_s - a));
      const auto first = static_cast<int64_t>(std::ceil(a * fs));
      const auto last = std::min<int64_t>(n, static_cast<int64_t>(std::ceil(b_s * fs)));
      for (int64_t t = std::max<int64_t>(first, 0); t < last; ++t) {
        const double time = static_cast<double>(t) / fs, into = std::min(time - a, b_s - time);
        gate[static_cast<size_t>(t)] =
            into >= edge ? 1.0 : 0.5 - 0.5 * std::cos(std::numbers::pi * std::max(0.0, into) / edge);
      }
    }
    const double level = std::pow(10.0, s.level_db / 20.0);
    RoomSource source;
    source.position_m = s.position_m;
    source.signal.resize(static_cast<size_t>(n));
    for (size_t t = 0; t < source.signal.size(); ++t) source.signal[t] = level * gate[t] * signal[t];
    sources.push_back(std::move(source));
  }
  auto rendered = RenderInRoom(scene.room, sources, sensors_m, fs, n);
  if (!rendered.ok()) return rendered.status();
  out.samples = std::move(rendered).value();
  std::seed_seq seq{seed, uint64_t{0x4e4f495345}};  // "NOISE"
  std::mt19937_64 rng(seq);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const double noise_sd = std::pow(10.0, scene.noise_db / 20.0) / (4.0 * std::numbers::pi);
  for (float& v : out.samples) v += static_cast<float>(noise_sd * gauss(rng));
  return out;
}

}  // namespace localizer::engine
