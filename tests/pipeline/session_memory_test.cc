// SessionMemoryBytes against the heap a session really holds: for a spread of configs
// (particles, channels, frame length, filter kind), the heap in use (glibc's mallinfo2:
// small blocks and mmapped ones) after Create and after processing two blocks never exceeds
// the estimate, and the estimate is within kLooseness of it -- admission by cost refuses
// what would not fit, and does not refuse much that would.
// LOCALIZER_MEMORY_PROBE=1 prints each config's measurement (how the coefficients were set).
#include "engine/pipeline/session_memory.h"

#include <gtest/gtest.h>
#include <malloc.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "engine/pipeline/locate.h"
#include "engine/pipeline/scan_session.h"
#include "engine/pipeline/session.h"

namespace localizer::engine {
namespace {

constexpr double kLooseness = 4.0;            // estimate / measured at most (small configs excepted)
constexpr int64_t kSmall = int64_t{4} << 20;  // below this, only the upper bound is checked

int64_t HeapInUse() {
  const struct mallinfo2 m = mallinfo2();
  return static_cast<int64_t>(m.uordblks + m.hblkhd);
}

bool Probe() {
  // There is no thread-safe getenv; it races only with setenv/putenv, which nothing here calls.
  // NOLINTNEXTLINE(concurrency-mt-unsafe): read-only, nothing in this process sets the environment
  return std::getenv("LOCALIZER_MEMORY_PROBE") != nullptr;
}

// Sensors on a sphere of radius 1 m (never coplanar for >= 4).
std::vector<Vec3> Sphere(int n) {
  std::vector<Vec3> out;
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - z * z), phi = 2.399963 * i;
    out.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  return out;
}

struct Measured {
  int64_t held = 0;
  int64_t estimate = 0;
};

Measured MeasureAudio(const AudioSessionConfig& config) {
  std::mt19937_64 rng(7);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  const int channels = static_cast<int>(config.sensors_m.size());
  const int64_t block = 2 * static_cast<int64_t>(config.frame_samples);
  std::vector<float> samples(static_cast<size_t>(channels * block));
  for (float& s : samples) s = noise(rng);
  const int64_t before = HeapInUse();
  int64_t held = 0;
  {
    auto session = Session::Create(config);
    EXPECT_TRUE(session.ok()) << session.status().ToString();
    if (!session.ok()) return {};
    held = HeapInUse() - before;
    std::vector<Estimate> out;
    for (int k = 0; k < 2; ++k) {
      EXPECT_TRUE((*session)->Process({static_cast<uint64_t>(k + 1), channels, block, samples.data()}, &out).ok());
      held = std::max(held, HeapInUse() - before);
    }
  }
  return {held, SessionMemoryBytes(config)};
}

void Check(const char* what, const Measured& m) {
  if (Probe()) {
    const double held = static_cast<double>(m.held), estimate = static_cast<double>(m.estimate);
    std::printf("%-44s held %9.2f MiB  estimate %9.2f MiB  ratio %.2f\n", what, held / 1048576.0, estimate / 1048576.0,
                estimate / static_cast<double>(std::max<int64_t>(m.held, 1)));
  }
  EXPECT_GE(m.estimate, m.held) << what;
  if (m.held > kSmall) {
    EXPECT_LE(static_cast<double>(m.estimate), kLooseness * static_cast<double>(m.held)) << what;
  }
}

TEST(SessionMemory, TheEstimateBoundsWhatAnAudioSessionHolds) {
  struct Case {
    int channels, frame, particles;
    FilterKind kind;
  };
  const std::vector<Case> cases = {
      {4, 4096, 4096, FilterKind::kPf},   {4, 4096, 65536, FilterKind::kPf},   {4, 4096, 262144, FilterKind::kPf},
      {4, 65536, 4096, FilterKind::kPf},  {8, 16384, 16384, FilterKind::kPf},  {16, 4096, 4096, FilterKind::kPf},
      {16, 65536, 4096, FilterKind::kPf}, {32, 8192, 8192, FilterKind::kPf},   {4, 4096, 65536, FilterKind::kMmpf},
      {4, 4096, 4096, FilterKind::kEkf},  {8, 262144, 1024, FilterKind::kImm}, {4, 1 << 20, 4096, FilterKind::kPf},
  };
  for (const Case& c : cases) {
    AudioSessionConfig config;
    config.sensors_m = Sphere(c.channels);
    config.sound_speed_mps = 343.0;
    config.sample_rate_hz = 48000.0;
    config.frame_samples = c.frame;
    config.hop_samples = c.frame / 2;
    config.tracker.kind = c.kind;
    config.tracker.particle.particles = c.particles;
    char what[96];
    std::snprintf(what, sizeof what, "%s ch=%d frame=%d particles=%d", FilterKindName(c.kind), c.channels, c.frame,
                  c.particles);
    Check(what, MeasureAudio(config));
  }
}

// Direction sessions (planar and linear arrays, or localization direction): every pair's
// cross-spectra, now and over the frames a rise looks back on (frame / hop of them).
TEST(SessionMemory, TheEstimateBoundsADirectionSession) {
  struct Case {
    int channels, frame, hop;
    bool planar;
  };
  const std::vector<Case> cases = {
      {4, 512, 256, true}, {7, 2048, 32, true}, {8, 4096, 1024, true}, {16, 8192, 2048, false}, {32, 2048, 512, false},
  };
  for (const Case& c : cases) {
    AudioSessionConfig config;
    config.sensors_m = Sphere(c.channels);
    if (c.planar) {
      for (Vec3& s : config.sensors_m) s.z() = 0.0, s *= 0.1;  // a 20 cm disc
    }
    config.localization = Localization::kDirection;
    config.sound_speed_mps = 343.0;
    config.sample_rate_hz = 16000.0;
    config.frame_samples = c.frame;
    config.hop_samples = c.hop;
    char what[96];
    std::snprintf(what, sizeof what, "direction ch=%d frame=%d hop=%d%s", c.channels, c.frame, c.hop,
                  c.planar ? " planar" : "");
    Check(what, MeasureAudio(config));
  }
  // The largest config the wire allows is charged what it would take, so a budget refuses it.
  AudioSessionConfig huge;
  huge.sensors_m = Sphere(64);
  huge.localization = Localization::kDirection;
  huge.sound_speed_mps = 343.0;
  huge.sample_rate_hz = 48000.0;
  huge.frame_samples = 1 << 20;
  huge.hop_samples = (1 << 20) / 64;
  EXPECT_GT(SessionMemoryBytes(huge), int64_t{100} << 30);  // over 100 GiB
}

TEST(SessionMemory, TheEstimateBoundsADetectionSessionAtItsLimits) {
  // The tracker at max_tracks with every gate saturated: the worst a scan can make it hold.
  DetectionSessionConfig config;
  config.tws.max_tracks = 4000;
  config.tws.max_plots_per_scan = 4000;
  const int64_t before = HeapInUse();
  int64_t held = 0;
  {
    auto session = ScanSession::Create(config);
    ASSERT_TRUE(session.ok());
    Scan crowd;
    crowd.detections.assign(4000, {5000.0, 0.25, std::nullopt, std::nullopt});
    ScanResult result;
    for (int k = 0; k < 3; ++k) {
      crowd.time_s = 1.0 + k;
      ASSERT_TRUE((*session)->Process(crowd, &result).ok());
      held = std::max(held, HeapInUse() - before);
    }
  }
  Check("detections max_tracks=4000 co-located", {held, SessionMemoryBytes(config)});
}

TEST(SessionMemory, TheEstimateBoundsALocateCall) {
  for (const int samples : {4096, 262144, 1 << 20}) {
    AudioSessionConfig config;
    config.sensors_m = Sphere(8);
    config.sound_speed_mps = 1500.0;
    config.sample_rate_hz = 96000.0;
    std::mt19937_64 rng(3);
    std::normal_distribution<float> noise(0.0f, 1.0f);
    std::vector<float> block(static_cast<size_t>(8) * samples);
    for (float& s : block) s = noise(rng);
    const int64_t before = HeapInUse();
    auto result = Locate(config, {1, 8, samples, block.data()});
    const int64_t held = HeapInUse() - before;  // what it left behind: nothing
    ASSERT_TRUE(result.ok()) << result.status().ToString();
    EXPECT_LT(held, int64_t{1} << 20);
    // Its peak is not observable from outside; the estimate must at least cover the block
    // and its spectra (the decoded copy the server holds, channels x samples float; each
    // channel's spectrum, complex float over 2 x samples).
    const int64_t floor = int64_t{8} * samples * (4 + 8);
    EXPECT_GE(LocateMemoryBytes(config, samples), floor) << samples;
  }
}

}  // namespace
}  // namespace localizer::engine
