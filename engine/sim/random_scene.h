// Scenes drawn at random from a seed: the measuring instrument for a tracker that was tuned on
// the named scenarios (scenarios.cc) and must be judged on scenes it has never seen.
//
// What one seed draws (all from one std::mt19937_64 seeded by the seed, in a fixed order, so
// the same seed gives the same scene in one build):
//   class     gaussian / multipath / impulsive, equally likely (or forced by the options; the
//             rest of the draw is the same either way, only the class-specific parts differ)
//   geometry  half the scenes a 4-sensor irregular tetrahedron (a regular one, each corner
//             moved by up to 15 % of the aperture per axis, randomly rotated), half 6-8
//             sensors spread in a ball (no two closer than 15 % of the aperture, the
//             thinnest principal axis at least 20 % of the widest: never coplanar); aperture
//             (largest sensor distance) log-uniform in [0.2, 40] m
//   medium    water (c = 1500 m/s, 11025 or 16000 Hz) or air (c = 343 m/s, 16000 or 48000 Hz);
//             air only for apertures up to 5 m (microphone arrays), water always possible
//   source    range log-uniform in [0.3, 5] apertures from the array centre, direction
//             uniform on the sphere; speed uniform in [0, 5] m/s (below 0.3 c), heading
//             uniform in azimuth with elevation within +-20 degrees; half constant velocity,
//             half turning at 0.05-0.5 rad/s either way. A track that comes within 10 % of
//             an aperture of a sensor or leaves 10 apertures from the centre is redrawn (a
//             few times, then the speed cap shrinks): the scene stays in the array's reach.
//   placement water: everything (array and the whole track) at least 0.5 m below the
//             surface z = 0; air: the lowest point of the scene at 0.3-1.5 m above a floor
//   SNR       uniform in [-5, 20] dB per channel
//   spectrum  a third each: broadband in a random band, low-pass (band_low_hz = 0),
//             3 tones carrying 30-80 % of the power plus broadband (SourceSignal)
//   multipath class: water: surface echo (-0.95 to -0.6) and, 70 % of the time, a bottom
//             echo (+0.2 to +0.7) 0.2-2 apertures (at least 0.5 m) below the scene; air: a
//             floor echo (+0.3 to +0.8) and, half the time, a ceiling echo (+0.3 to +0.8)
//             0.5-2 m above the scene
//   impulsive class: alpha-stable impulses on 0.2-2 % of the samples (log-uniform), scale
//             10-50 x the Gaussian noise std, alpha in [1.2, 1.8]
// The simulator's seed is the scene's seed, so the noise and source signal follow it too.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "engine/core/status.h"
#include "engine/sim/simulator.h"

namespace localizer::engine {

enum class SceneClass { kGaussian, kMultipath, kImpulsive };

const char* SceneClassName(SceneClass scene_class);  // "gaussian" | "multipath" | "impulsive"
// INVALID_ARGUMENT naming the valid names for anything else.
StatusOr<SceneClass> ParseSceneClass(const std::string& name);

struct RandomSceneOptions {
  double duration_s = 12.0;               // > 0
  std::optional<SceneClass> scene_class;  // unset: drawn from the seed
  double truth_step_s = 0.01;
};

struct RandomScene {
  uint64_t seed = 0;
  SceneClass scene_class = SceneClass::kGaussian;
  // Sensors, sound speed and SimOptions (sim.seed = seed), named "random-<seed>", with a
  // one-line description of what was drawn.
  Scenario scenario;
  std::string medium;          // "water" | "air"
  double aperture_m = 0.0;     // largest distance between two sensors
  double start_range_m = 0.0;  // source to array centre at t = 0
};

// INVALID_ARGUMENT when the options are out of range (naming the field).
StatusOr<RandomScene> DrawRandomScene(uint64_t seed, const RandomSceneOptions& options = {});

}  // namespace localizer::engine
