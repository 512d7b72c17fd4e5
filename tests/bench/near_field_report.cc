// Positions from a linear array in a stated plane, on randomised reverberant rooms: the
// issue-18 goal (median error within 1.2 x a per-frame least-squares fix on all pairs),
// measured. Not a test (no pass/fail); numbers for ACCURACY.md.
//
// Per scene (seeded): a shoebox of 4-8 x 4-7 x 2.5-3.5 m; an 8-microphone line, 0.05-0.15 m
// spacing, along x at 0.5-1.5 m from the y = 0 wall and 1-2 m high, horizontal plane through
// it stated, side +y; one white-noise talker in that plane at 1-3 apertures, 30-150 degrees
// from the axis; sensor noise 20 dB below the direct sound at 1 m; 16 kHz, frames of 1024,
// hop 512, 3 s. Scored: every frame's position from the session against the truth, and a
// per-frame least-squares fix on every pair's GCC-PHAT peak started at the truth
// (tests/doa/near_field_scene.h). Per RT60 it prints the median over scenes of each
// scene's median error, their ratio, the share of frames with a position, the median
// ratio of error to the reported range sd, and the session's median time per frame (the
// spatial spectrum, the tracker and the near-field fit; 32 ms of audio per hop) beside a
// direction session's on the same audio (the difference is the fit's cost).
//
// --array circle instead: 8 microphones on a horizontal circle of 0.15-0.45 m radius, the
// talker above it (source_side +z) at 1-3 apertures and 15-60 degrees of elevation; the
// least-squares fix is then 3-D.
//
//   build/tests/bench/near_field_report [--scenes 10] [--seed 1] [--array line|circle]
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "engine/core/flags.h"
#include "engine/pipeline/session.h"
#include "tests/doa/near_field_scene.h"

namespace localizer::engine {
namespace {

using testing::LeastSquaresFixes;
using testing::Median;

int Run(int scenes, uint64_t seed, bool circle) {
  std::printf("RT60 s | scenes | median error, session (m) | least squares (m) | ratio | frames with a position | "
              "error / range sd | frame ms (median) | directions only, frame ms (median)\n");
  for (const double rt60_s : {0.0, 0.2, 0.4, 0.6}) {
    std::vector<double> ours, theirs, ratios, coverage, normalised, frame_ms, direction_frame_ms;
    for (int k = 0; k < scenes; ++k) {
      std::mt19937_64 rng(seed * 1000003 + static_cast<uint64_t>(k));
      std::uniform_real_distribution<double> u01(0.0, 1.0);
      const auto in = [&](double a, double b) { return a + (b - a) * u01(rng); };
      testing::NearFieldScene scene;
      scene.room.size_m = Vec3(in(4, 8), in(4, 7), in(2.5, 3.5));
      scene.room.rt60_s = rt60_s;
      scene.seconds = 3.0;
      scene.seed = rng();
      AudioSessionConfig c;
      c.sound_speed_mps = 343.0;
      c.sample_rate_hz = 16000.0;
      c.frame_samples = 1024;
      c.hop_samples = 512;
      c.max_sources = 1;
      Vec3 centre_m, source_m, plane_normal = Vec3::UnitZ();
      double aperture_m = 0.0;
      if (circle) {
        // 8 microphones on a horizontal circle of radius 0.15-0.45 m, 0.8-1.2 m high; the
        // talker above it (side +z) at 1-3 apertures, 15-60 degrees of elevation.
        const double radius_m = in(0.15, 0.45), z_m = in(0.8, 1.2);
        centre_m = Vec3(0.5 * scene.room.size_m.x(), 0.5 * scene.room.size_m.y(), z_m);
        for (int i = 0; i < 8; ++i) {
          const double a = 2.0 * std::numbers::pi * i / 8.0;
          scene.sensors_m.push_back(centre_m + radius_m * Vec3(std::cos(a), std::sin(a), 0.0));
        }
        aperture_m = 2.0 * radius_m;
        plane_normal = Vec3::Zero();  // the least-squares fix is 3-D
        c.localization = Localization::kPosition;
        c.source_side = Vec3::UnitZ();
      } else {
        const double spacing_m = in(0.05, 0.15);
        const double y_m = in(0.5, 1.5), z_m = in(1.0, 2.0);
        const double x0_m = 0.5 * (scene.room.size_m.x() - 7 * spacing_m);
        for (int i = 0; i < 8; ++i) scene.sensors_m.emplace_back(x0_m + i * spacing_m, y_m, z_m);
        centre_m = Vec3(x0_m + 3.5 * spacing_m, y_m, z_m);
        aperture_m = 7 * spacing_m;
        c.source_plane_point_m = centre_m;
        c.source_plane_normal = Vec3::UnitZ();
        c.source_side = Vec3::UnitY();
      }
      for (int attempt = 0; attempt < 100; ++attempt) {
        const double range_m = in(1.0, 3.0) * aperture_m;
        Vec3 u;
        if (circle) {
          const double azimuth = in(-std::numbers::pi, std::numbers::pi);
          const double elevation = in(15.0, 60.0) * std::numbers::pi / 180.0;
          u = Vec3(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                   std::sin(elevation));
        } else {
          const double angle = in(30.0, 150.0) * std::numbers::pi / 180.0;
          u = Vec3(std::cos(angle), std::sin(angle), 0.0);
        }
        source_m = centre_m + range_m * u;
        const Vec3 margin = Vec3::Constant(0.3);
        if ((source_m - margin).minCoeff() > 0.0 && (scene.room.size_m - source_m - margin).minCoeff() > 0.0) break;
      }
      scene.sources_m = {source_m};
      c.sensors_m = scene.sensors_m;
      auto session = Session::Create(c);
      if (!session.ok()) {
        std::fprintf(stderr, "scene %d: %s\n", k, session.status().message().c_str());
        return 1;
      }
      const auto samples = testing::RenderNearFieldScene(scene);
      const auto estimates = testing::StreamThrough(session->get(), samples, 8);
      // The same audio asked for directions only: the fit's cost is the difference.
      AudioSessionConfig directions = c;
      directions.localization = Localization::kDirection;
      auto direction_session = Session::Create(directions);
      if (direction_session.ok()) {
        for (const Estimate& e : testing::StreamThrough(direction_session->get(), samples, 8)) {
          direction_frame_ms.push_back(e.timings.tdoa_s * 1e3);
        }
      }
      std::vector<double> errors_m, per_sd, ls_m;
      for (const Estimate& e : estimates) {
        frame_ms.push_back(e.timings.tdoa_s * 1e3);
        for (const SourceEstimate& s : e.sources) {
          if (!s.position_m.allFinite()) continue;
          errors_m.push_back((s.position_m - source_m).norm());
          per_sd.push_back(errors_m.back() / s.range_sd_m);
        }
      }
      for (const Vec3& fix : LeastSquaresFixes(samples, c.sensors_m, 16000.0, 343.0, 1024, 512, source_m,
                                               plane_normal)) {
        ls_m.push_back((fix - source_m).norm());
      }
      const double mine = errors_m.empty() ? INFINITY : Median(errors_m);
      ours.push_back(mine);
      theirs.push_back(Median(ls_m));
      ratios.push_back(mine / Median(ls_m));
      coverage.push_back(estimates.empty() ? 0.0 : static_cast<double>(errors_m.size()) / static_cast<double>(estimates.size()));
      if (!per_sd.empty()) normalised.push_back(Median(per_sd));
    }
    std::printf("%.1f | %d | %.4f | %.4f | %.2f | %.2f | %.2f | %.2f | %.2f\n", rt60_s, scenes, Median(ours),
                Median(theirs), Median(ratios), Median(coverage), Median(normalised), Median(frame_ms),
                Median(direction_frame_ms));
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace
}  // namespace localizer::engine

int main(int argc, char** argv) {
  int scenes = 10;
  uint64_t seed = 1;
  std::string shape = "line";
  localizer::FlagSet flags("near_field_report [flags]",
                           "Positions from an 8-microphone line in randomised rooms (RT60 0, 0.2, 0.4, 0.6 s)\n"
                           "against a per-frame least-squares fix on all pairs; one line per RT60.");
  flags.Int("scenes", &scenes, "N", "scenes", "scenes per RT60, in [1, 1000]");
  flags.Uint64("seed", &seed, "N", "rooms, arrays, talkers and noise");
  flags.String("array", &shape, "SHAPE", "line (in its horizontal plane) or circle (a planar array, talker above)");
  const localizer::Status parsed = flags.Parse(std::vector<std::string>(argv + 1, argv + argc));
  if (flags.help_requested()) return std::printf("%s", flags.Usage().c_str()), 0;
  if (!parsed.ok()) return std::fprintf(stderr, "near_field_report: %s\n", parsed.message().c_str()), 2;
  if (scenes < 1 || scenes > 1000) return std::fprintf(stderr, "near_field_report: --scenes must be in [1, 1000]\n"), 2;
  if (shape != "line" && shape != "circle") {
    return std::fprintf(stderr, "near_field_report: --array must be line or circle\n"), 2;
  }
  return localizer::engine::Run(scenes, seed, shape == "circle");
}
