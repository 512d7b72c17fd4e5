// Two sources at once around an array that gives positions (issue 18): seeded rooms, scored
// per RT60 (0 and 0.3 s) by how many source-frames a heard row covers within 10 degrees, and
// how the positions compare with their reported range sd. For the large-array search and
// tracker options (AudioSessionConfig::direction_search_starts, direction_co_lead_share):
// ACCURACY.md, "Large arrays and several sources".
//
// Scenes: a room of 6 x 5 x 3 m (--far: 20 x 20 x 6 m), the array at a random place (the
// tetrahedron also randomly rotated), two white sources at least 60 degrees apart (45 for the
// circle and line) as the array sees them, 0.6-2 m from its centroid (--far, tetrahedron: 6-9
// m), 3 s, sensor noise 20 dB below a source at 1 m (--far: 40 dB), 1024/512 frames at 16 kHz,
// max_sources 2.
// Arrays: tetra (0.5-m edges, volumetric), circle (8 microphones, 0.3-m radius, horizontal,
// sources above: source_side +z), line (8 microphones 0.1 m apart, sources in its horizontal
// plane on the +y side).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "engine/core/flags.h"
#include "engine/pipeline/session.h"
#include "tests/doa/near_field_scene.h"

namespace localizer::engine {
namespace {

using testing::Median;
using testing::NearFieldScene;
using testing::RenderNearFieldScene;
using testing::StreamThrough;

struct Options {
  std::string shape = "tetra";
  int scenes = 12;
  uint64_t seed = 1;
  bool far = false;
  int search_starts = 1;
  double co_lead_share = 0.0;
};

struct Scene {
  AudioSessionConfig config;
  NearFieldScene scene;
  Vec3 centroid_m = Vec3::Zero();
};

// Scene k of the options' seed, or false when no placement of the sources fits the room.
bool Draw(const Options& o, int k, double rt60_s, Scene* out) {
  std::mt19937_64 rng(o.seed * 1000003ULL + static_cast<uint64_t>(k));
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const Vec3 room = o.far ? Vec3(20.0, 20.0, 6.0) : Vec3(6.0, 5.0, 3.0);
  const Vec3 c = o.far ? Vec3(9.5 + u01(rng), 9.5 + u01(rng), 2.5 + 0.3 * u01(rng))
                       : Vec3(2.5 + u01(rng), 2.0 + u01(rng), 1.0 + 0.3 * u01(rng));
  AudioSessionConfig& config = out->config;
  config = AudioSessionConfig{};
  std::vector<Vec3>& sensors = config.sensors_m;
  double min_apart_rad = std::numbers::pi / 4;
  if (o.shape == "tetra") {
    const double a = 0.5 / (2.0 * std::sqrt(2.0));  // alternate cube corners: 0.5-m edges
    Eigen::Quaterniond q(u01(rng) - 0.5, u01(rng) - 0.5, u01(rng) - 0.5, u01(rng) - 0.5);
    const Mat3 r = q.normalized().toRotationMatrix();
    for (const Vec3& v : {Vec3(a, a, a), Vec3(a, -a, -a), Vec3(-a, a, -a), Vec3(-a, -a, a)})
      sensors.push_back(c + r * v);
    min_apart_rad = std::numbers::pi / 3;
  } else if (o.shape == "circle") {
    for (int i = 0; i < 8; ++i) {
      const double t = 2.0 * std::numbers::pi * i / 8.0;
      sensors.push_back(c + 0.3 * Vec3(std::cos(t), std::sin(t), 0.0));
    }
    config.source_side = Vec3::UnitZ();
  } else {
    for (int i = 0; i < 8; ++i) sensors.push_back(c + Vec3(0.1 * i - 0.35, 0.0, 0.0));
    config.source_plane_point_m = c;
    config.source_plane_normal = Vec3::UnitZ();
    config.source_side = Vec3::UnitY();
  }
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& s : sensors) centroid += s / static_cast<double>(sensors.size());
  std::vector<Vec3> sources;
  for (int tries = 0; sources.size() < 2 && tries < 1000; ++tries) {
    double azimuth = 2.0 * std::numbers::pi * u01(rng), elevation = (u01(rng) - 0.5) * 0.8;
    if (o.shape == "circle") elevation = 0.2 + 0.8 * u01(rng);
    if (o.shape == "line") azimuth = std::numbers::pi * (0.1 + 0.8 * u01(rng)), elevation = 0.0;
    const double range = o.far ? 6.0 + 3.0 * u01(rng) : 0.6 + 1.4 * u01(rng);
    const Vec3 u(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    const Vec3 p = centroid + range * u;
    if ((p.array() < 0.3).any() || (p.array() > room.array() - 0.3).any()) continue;
    if (!sources.empty() &&
        std::acos(std::clamp(u.dot((sources[0] - centroid).normalized()), -1.0, 1.0)) < min_apart_rad)
      continue;
    sources.push_back(p);
  }
  if (sources.size() < 2) return false;
  config.localization = Localization::kPosition;
  config.sound_speed_mps = 343.0;
  config.sample_rate_hz = 16000.0;
  config.frame_samples = 1024;
  config.hop_samples = 512;
  config.max_sources = 2;
  config.direction_search_starts = o.search_starts;
  config.direction_co_lead_share = o.co_lead_share;
  NearFieldScene& scene = out->scene;
  scene = NearFieldScene{};
  scene.room.size_m = room;
  scene.room.rt60_s = rt60_s;
  scene.sensors_m = sensors;
  scene.sources_m = sources;
  scene.seconds = 3.0;
  scene.snr_db = o.far ? 40.0 : 20.0;
  scene.seed = o.seed * 7919ULL + static_cast<uint64_t>(k);
  out->centroid_m = centroid;
  return true;
}

int Run(const Options& o) {
  std::printf("two_source_report: array %s, %s, %d scenes, seed %llu, search starts %d, co-lead share %.2f\n",
              o.shape.c_str(), o.far ? "far (6-9 m)" : "near (0.6-2 m)", o.scenes,
              static_cast<unsigned long long>(o.seed), o.search_starts, o.co_lead_share);
  std::printf(
      "RT60 s | source-frames | heard rows | within 10 deg | positions | median error (m) | error / range sd | "
      "within 3 sd | direction error (deg) | frame ms (median)\n");
  for (double rt60_s : {0.0, 0.3}) {
    size_t source_frames = 0, heard = 0, within = 0;
    std::vector<double> errors_m, ratios, direction_deg, frame_ms;
    for (int k = 0; k < o.scenes; ++k) {
      Scene s;
      if (!Draw(o, k, rt60_s, &s)) continue;
      auto session = Session::Create(s.config);
      if (!session.ok()) return std::fprintf(stderr, "two_source_report: %s\n", session.status().message().c_str()), 1;
      const std::vector<float> samples = RenderNearFieldScene(s.scene);
      const int sensors = static_cast<int>(s.config.sensors_m.size());
      for (const Estimate& e : StreamThrough(session->get(), samples, sensors)) {
        source_frames += 2;
        frame_ms.push_back(1e3 * e.timings.tdoa_s);
        for (const SourceEstimate& x : e.sources) {
          if (!x.source_present) continue;
          ++heard;
          double nearest_rad = std::numbers::pi;
          size_t nearest = 0;
          for (size_t j = 0; j < 2; ++j) {
            const Vec3 u = (s.scene.sources_m[j] - s.centroid_m).normalized();
            // A line reports cone angles; compare those.
            const double apart = std::isfinite(x.cone_angle_rad)
                                     ? std::abs(x.cone_angle_rad - std::acos(std::clamp(u.x(), -1.0, 1.0)))
                                     : std::acos(std::clamp(x.direction.dot(u), -1.0, 1.0));
            if (apart < nearest_rad) nearest_rad = apart, nearest = j;
          }
          direction_deg.push_back(nearest_rad * 180.0 / std::numbers::pi);
          within += nearest_rad < 10.0 * std::numbers::pi / 180.0;
          if (!x.position_m.allFinite()) continue;
          const double error_m = (x.position_m - s.scene.sources_m[nearest]).norm();
          errors_m.push_back(error_m);
          ratios.push_back(error_m / x.range_sd_m);
        }
      }
    }
    const double within_3sd =
        ratios.empty()
            ? 0.0
            : static_cast<double>(std::count_if(ratios.begin(), ratios.end(), [](double r) { return r < 3.0; })) /
                  static_cast<double>(ratios.size());
    std::printf("%.1f | %zu | %zu | %zu | %zu | %.4f | %.2f | %.2f | %.2f | %.3f\n", rt60_s, source_frames, heard,
                within, errors_m.size(), Median(errors_m), Median(ratios), within_3sd, Median(direction_deg),
                Median(frame_ms));
  }
  return 0;
}

}  // namespace
}  // namespace localizer::engine

int main(int argc, char** argv) {
  localizer::engine::Options o;
  localizer::FlagSet flags("two_source_report [flags]",
                           "Two sources at once around an array that gives positions, in seeded rooms (RT60 0 and\n"
                           "0.3 s); one line per RT60.");
  flags.String("array", &o.shape, "SHAPE", "tetra (0.5-m edges), circle (8, side above) or line (8, in its plane)");
  flags.Int("scenes", &o.scenes, "N", "scenes", "scenes per RT60, in [1, 1000]");
  flags.Uint64("seed", &o.seed, "N", "rooms, arrays, sources and noise");
  flags.Bool("far", &o.far, "tetra only: sources 6-9 m away in a 20 x 20 x 6 m room");
  flags.Int("search-starts", &o.search_starts, "N", "", "AudioSessionConfig::direction_search_starts, in [1, 64]");
  flags.Double("co-lead-share", &o.co_lead_share, "F", "",
               "AudioSessionConfig::direction_co_lead_share, in [0, 1] (0: off)");
  const localizer::Status parsed = flags.Parse(std::vector<std::string>(argv + 1, argv + argc));
  if (flags.help_requested()) return std::printf("%s", flags.Usage().c_str()), 0;
  if (!parsed.ok()) return std::fprintf(stderr, "two_source_report: %s\n", parsed.message().c_str()), 2;
  if (o.scenes < 1 || o.scenes > 1000)
    return std::fprintf(stderr, "two_source_report: --scenes must be in [1, 1000]\n"), 2;
  if (o.shape != "tetra" && o.shape != "circle" && o.shape != "line") {
    return std::fprintf(stderr, "two_source_report: --array must be tetra, circle or line\n"), 2;
  }
  if (o.far && o.shape != "tetra") return std::fprintf(stderr, "two_source_report: --far is for --array tetra\n"), 2;
  return localizer::engine::Run(o);
}
