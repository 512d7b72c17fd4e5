// scene_campaign: the tracker on scenes drawn at random (engine/sim/random_scene.h), scored
// against the per-frame CRLB (engine/pipeline/scene_campaign.h). A plain main, not Google
// Benchmark: it measures accuracy and robustness, not speed.
//
//   scene_campaign --scenes 200 --seed 1 [--json out.json] [--class all|gaussian|multipath|impulsive]
//                  [--duration 12] [--jobs 1]
//
// Scene i of a campaign has seed  seed * 1000000 + i, so `localizer-cli simulate --random
// <that seed>` writes the same recording (and a campaign seed never overlaps another's scenes).
#include "engine/pipeline/scene_campaign.h"

#include <atomic>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <optional>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

using namespace localizer::engine;

namespace {

struct Args {
  int scenes = 200;
  uint64_t seed = 1;
  std::string json_path;
  std::optional<SceneClass> scene_class;
  double duration_s = 12.0;
  int jobs = 1;
  std::optional<Weighting> weighting;                                       // unset: the session default
  std::optional<uint64_t> trace_seed;                                       // one scene, frame by frame
  std::optional<FilterKind> filter;                                         // unset: the session default
  int particles = 0;                                                        // 0: the session default
  double accel_noise_mps2 = -1.0;                                           // < 0: the session default
  double manoeuvre_share = -1.0;                                            // < 0: the session default
  int tempered_updates = -1;                                                // < 0: the session default
  double tempering_ess = -1.0;                                              // < 0: the session default
  double manoeuvre_scale = 0.0;                                             // < 1: the session default
  std::optional<Likelihood> likelihood;                                     // unset: the session default
  double outlier_probability = -1.0;                                        // < 0: the session default
  double kernel_scale = -1.0;                                               // < 0: the session default
  double level_floor = -1.0, level_ceiling = -1.0, level_switch_hz = -1.0;  // < 0: the default
  double turn_rate_max_radps = -1.0;                                        // < 0: the session default
  double speed_change_max_mps2 = -1.0;                                      // < 0: the session default
  int frame_samples = 0;             // --frame-samples: every scene's frame (hop half of it); 0: the campaign's
  bool band_hint = false;            // --band-hint: the session gets the scene's true band
  int cross_pairs_max_sensors = -1;  // --cross-pairs N; < 0: the session default
  int delay_rates = -1;              // --delay-rates 0|1; < 0: the session default
  int closure = -1;                  // --closure 0|1; < 0: the session default
  int fusion = -1;                   // --fusion 0|1; < 0: the session default
  double motion_blur = -1.0;         // --motion-blur K; < 0: the session default
  bool help = false;                 // --help: print the usage and exit 0
};

// The flags' changes to the campaign's default session config (`scene`: the one it runs).
void Adjust(const Args& a, const RandomSceneOptions& scene_options, AudioSessionConfig* c) {
  if (a.band_hint) {  // an oracle: what a perfect band estimate would give (c->seed is the scene's)
    if (auto scene = DrawRandomScene(c->seed, scene_options); scene.ok()) {
      c->band_low_hz = scene->scenario.sim.band_low_hz;
      c->band_high_hz = scene->scenario.sim.band_high_hz;
    }
  }
  if (a.weighting) c->weighting = *a.weighting;
  if (a.frame_samples > 0) {
    c->frame_samples = a.frame_samples;
    c->hop_samples = a.frame_samples / 2;
  }
  if (a.cross_pairs_max_sensors >= 0) c->cross_pairs_max_sensors = a.cross_pairs_max_sensors;
  if (a.delay_rates >= 0) c->delay_rate_compensation = a.delay_rates == 1;
  if (a.closure >= 0) c->pair_closure = a.closure == 1;
  if (a.fusion >= 0) c->pair_fusion = a.fusion == 1;
  if (a.motion_blur >= 0.0) c->tracker.particle.motion_blur = a.motion_blur;
  if (a.filter) c->tracker.kind = *a.filter;
  if (a.particles > 0) c->tracker.particle.particles = a.particles;
  if (a.manoeuvre_share >= 0.0) c->tracker.particle.manoeuvre_share = a.manoeuvre_share;
  if (a.manoeuvre_scale >= 1.0) c->tracker.particle.manoeuvre_scale = a.manoeuvre_scale;
  if (a.tempered_updates >= 0) c->tracker.particle.tempered_updates = a.tempered_updates;
  if (a.tempering_ess >= 0.0) c->tracker.particle.tempering_ess_fraction = a.tempering_ess;
  if (a.likelihood) c->tracker.particle.likelihood = *a.likelihood;
  if (a.outlier_probability >= 0.0) c->tracker.particle.outlier_probability = a.outlier_probability;
  if (a.kernel_scale >= 0.0) c->tracker.particle.kernel_scale = a.kernel_scale;
  if (a.level_floor > 0.0) {
    c->tracker.particle.accel_level_floor = a.level_floor;
    c->tracker.particle.accel_level_ceiling = a.level_ceiling;
    c->tracker.particle.accel_level_switch_hz = a.level_switch_hz;
  }
  if (a.turn_rate_max_radps >= 0.0) c->tracker.particle.turn_rate_max_radps = a.turn_rate_max_radps;
  if (a.speed_change_max_mps2 >= 0.0) c->tracker.particle.speed_change_max_mps2 = a.speed_change_max_mps2;
  if (a.accel_noise_mps2 >= 0.0) {
    c->tracker.particle.accel_noise_mps2 = a.accel_noise_mps2;
    c->tracker.kalman.motion.accel_noise_mps2 = a.accel_noise_mps2;
  }
}

void Usage(FILE* out) {
  std::fprintf(
      out,
      "usage: scene_campaign [--scenes N] [--seed S] [--json FILE] [--class all|gaussian|multipath|impulsive]\n"
      "                      [--duration SECONDS] [--jobs J] [--weighting phat|phat-coherence|...]\n"
      "                      [--filter pf|ekf|ukf|mmpf|imm] [--particles N] [--accel-noise MPS2]\n"
      "                      [--manoeuvre-share P] [--manoeuvre-scale K] [--tempered-updates N]\n"
      "                      [--tempering-ess F]\n"
      "                      [--likelihood peak|gcc|mixture] [--outlier-probability EPS]\n"
      "                      [--kernel-scale H] [--accel-levels FLOOR,CEILING,HZ] [--turn-rates MAX]\n"
      "                      [--speed-changes MAX] [--band-hint] [--frame-samples N] [--cross-pairs N]\n"
      "                      [--delay-rates 0|1] [--closure 0|1] [--fusion 0|1] [--motion-blur K]\n"
      "                      [--trace SEED]\n"
      "Runs N random scenes (scene i has seed S*1000000+i) through an engine Session with a default\n"
      "config (no band hint) and scores each against the per-frame CRLB: time to acquire (error\n"
      "within 3 x CRLB to the end), RMSE/CRLB and median NEES/dim after acquisition, lost frames\n"
      "(> 10 x CRLB after a first good frame), silent failures (> 1 s of error > 10 x CRLB with\n"
      "position NEES > 50 while initialised, present, not ambiguous). Also scored in bearing from the\n"
      "array's centroid against the bearing CRLB (column brg; r_aper: the truth's median range in\n"
      "apertures): what an array gives where it cannot see range. And as reported (column rep):\n"
      "frames whose estimate says far field (range unobservable) judged in bearing, the others in\n"
      "position; far: how many frames said far field.\n"
      "--weighting, --filter, --particles, --accel-noise (the motion model's white acceleration\n"
      "std, m/s^2) and --manoeuvre-share/--manoeuvre-scale (particle filter: the share of particles\n"
      "whose acceleration std is scaled each step) and --tempered-updates (particle filter: updates\n"
      "after each (re)start tempered in stages), --tempering-ess (particle filter: an update whose\n"
      "ESS would fall below this fraction of N is split into stages), --likelihood,\n"
      "--outlier-probability (the mixture\n"
      "likelihood's eps), --kernel-scale (the particle filter's regularisation) and\n"
      "--accel-levels (its acceleration levels, e.g. 0.003,3,1; particle_filter.h) and --turn-rates\n"
      "(its per-particle turn rates up to MAX rad/s about +z, e.g. 1) and --speed-changes (its\n"
      "per-particle accelerations along the velocity up to MAX m/s^2, e.g. 1) override the\n"
      "session's defaults.\n"
      "--frame-samples N gives every session frames of N samples, hop N/2 (the service's default is\n"
      "4096 at any rate); without it the campaign uses about a quarter second per frame: 4096 up to\n"
      "16 kHz, 16384 at 48 kHz. The per-frame CRLB is that of the frames the session uses.\n"
      "--cross-pairs N: arrays of at most N sensors also measure the pairs without the reference\n"
      "(0: never; the session's default is 8; session_config.h, cross_pairs_max_sensors).\n"
      "--delay-rates 0|1: a track's predicted delay rates read each channel along its pair's delay\n"
      "when a peak would move by a sample or more in a frame (session_config.h,\n"
      "delay_rate_compensation; the session's default is 0).\n"
      "--closure 0|1: small arrays' tracked frames also measure the pairs without the reference and\n"
      "move a reference pair they contradict (session_config.h, pair_closure; default 1).\n"
      "--fusion 0|1: arrays that measure the pairs without the reference fold every pair's peak\n"
      "into the reference pairs' delays on tracked frames (session_config.h, pair_fusion; default 1).\n"
      "--motion-blur K: the particle filter widens each particle's pair likelihood by K x the spread its\n"
      "own delay rate gives the frame's peak (particle_filter.h, motion_blur; default 0: off).\n"
      "--band-hint gives each session its scene's true source band (an oracle: what a perfect band\n"
      "estimate from the data would give; the campaign's default gives none).\n"
      "--trace SEED runs that one scene (a full seed, e.g. 1000021) and prints every frame: time,\n"
      "initialised, present, ambiguous, far field, silent (the frame adds to silent_failure_s), true range,\n"
      "range error, error, CRLB, error/CRLB, bearing error/its CRLB, reported sd, position NEES.\n"
      "Defaults: --scenes 200 --seed 1 --class all --duration 12 --jobs 1.\n");
}

bool ParseArgs(int argc, char** argv, Args* a) {
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") {
      a->help = true;
      return true;
    }
    if (flag == "--band-hint") {  // takes no value
      a->band_hint = true;
      continue;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "scene_campaign: %s needs a value\n", flag.c_str());
      return false;
    }
    const std::string value = argv[++i];
    char* end = nullptr;
    if (flag == "--scenes") {
      a->scenes = static_cast<int>(std::strtol(value.c_str(), &end, 10));
      if (*end != '\0' || a->scenes < 1) return std::fprintf(stderr, "scene_campaign: --scenes must be >= 1\n"), false;
    } else if (flag == "--seed") {
      a->seed = std::strtoull(value.c_str(), &end, 10);
      if (*end != '\0') return std::fprintf(stderr, "scene_campaign: --seed must be an integer\n"), false;
    } else if (flag == "--filter") {
      auto parsed = ParseFilterKind(value, "--filter");
      if (!parsed.ok()) return std::fprintf(stderr, "scene_campaign: %s\n", parsed.status().ToString().c_str()), false;
      a->filter = *parsed;
    } else if (flag == "--particles") {
      a->particles = static_cast<int>(std::strtol(value.c_str(), &end, 10));
      if (*end != '\0' || a->particles < 1)
        return std::fprintf(stderr, "scene_campaign: --particles must be >= 1\n"), false;
    } else if (flag == "--accel-noise") {
      a->accel_noise_mps2 = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(a->accel_noise_mps2 >= 0.0))
        return std::fprintf(stderr, "scene_campaign: --accel-noise must be >= 0\n"), false;
    } else if (flag == "--manoeuvre-share") {
      a->manoeuvre_share = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(a->manoeuvre_share >= 0.0 && a->manoeuvre_share < 1.0))
        return std::fprintf(stderr, "scene_campaign: --manoeuvre-share must be in [0, 1)\n"), false;
    } else if (flag == "--manoeuvre-scale") {
      a->manoeuvre_scale = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(a->manoeuvre_scale >= 1.0))
        return std::fprintf(stderr, "scene_campaign: --manoeuvre-scale must be >= 1\n"), false;
    } else if (flag == "--likelihood") {
      auto parsed = ParseLikelihood(value);
      if (!parsed.ok()) return std::fprintf(stderr, "scene_campaign: %s\n", parsed.status().ToString().c_str()), false;
      a->likelihood = *parsed;
    } else if (flag == "--outlier-probability") {
      a->outlier_probability = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(a->outlier_probability >= 0.0 && a->outlier_probability < 1.0))
        return std::fprintf(stderr, "scene_campaign: --outlier-probability must be in [0, 1)\n"), false;
    } else if (flag == "--kernel-scale") {
      a->kernel_scale = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(a->kernel_scale >= 0.0 && a->kernel_scale <= 2.0))
        return std::fprintf(stderr, "scene_campaign: --kernel-scale must be in [0, 2]\n"), false;
    } else if (flag == "--accel-levels") {
      if (std::sscanf(value.c_str(), "%lf,%lf,%lf", &a->level_floor, &a->level_ceiling, &a->level_switch_hz) != 3 ||
          !(a->level_floor > 0.0))
        return std::fprintf(stderr, "scene_campaign: --accel-levels takes FLOOR,CEILING,HZ (floor > 0)\n"), false;
    } else if (flag == "--turn-rates") {
      a->turn_rate_max_radps = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(a->turn_rate_max_radps >= 0.0 && a->turn_rate_max_radps <= 5.0))
        return std::fprintf(stderr, "scene_campaign: --turn-rates must be in [0, 5] rad/s\n"), false;
    } else if (flag == "--speed-changes") {
      a->speed_change_max_mps2 = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(a->speed_change_max_mps2 >= 0.0 && a->speed_change_max_mps2 <= 20.0))
        return std::fprintf(stderr, "scene_campaign: --speed-changes must be in [0, 20] m/s^2\n"), false;
    } else if (flag == "--tempered-updates") {
      a->tempered_updates = static_cast<int>(std::strtol(value.c_str(), &end, 10));
      if (*end != '\0' || a->tempered_updates < 0 || a->tempered_updates > 100)
        return std::fprintf(stderr, "scene_campaign: --tempered-updates must be in [0, 100]\n"), false;
    } else if (flag == "--tempering-ess") {
      a->tempering_ess = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(a->tempering_ess >= 0.0 && a->tempering_ess <= 1.0))
        return std::fprintf(stderr, "scene_campaign: --tempering-ess must be in [0, 1]\n"), false;
    } else if (flag == "--trace") {
      a->trace_seed = std::strtoull(value.c_str(), &end, 10);
      if (*end != '\0') return std::fprintf(stderr, "scene_campaign: --trace must be a scene seed\n"), false;
    } else if (flag == "--json") {
      a->json_path = value;
    } else if (flag == "--class") {
      if (value == "all") {
        a->scene_class.reset();
      } else {
        auto parsed = ParseSceneClass(value);
        if (!parsed.ok())
          return std::fprintf(stderr, "scene_campaign: --class: %s\n", parsed.status().ToString().c_str()), false;
        a->scene_class = *parsed;
      }
    } else if (flag == "--duration") {
      a->duration_s = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(a->duration_s > 0.0))
        return std::fprintf(stderr, "scene_campaign: --duration must be > 0\n"), false;
    } else if (flag == "--weighting") {
      auto parsed = ParseWeighting(value);
      if (!parsed.ok())
        return std::fprintf(stderr, "scene_campaign: --weighting: %s\n", parsed.status().ToString().c_str()), false;
      a->weighting = *parsed;
    } else if (flag == "--frame-samples") {
      a->frame_samples = static_cast<int>(std::strtol(value.c_str(), &end, 10));
      if (*end != '\0' || a->frame_samples < 64 || a->frame_samples > (1 << 20))
        return std::fprintf(stderr, "scene_campaign: --frame-samples must be in [64, 2^20]\n"), false;
    } else if (flag == "--delay-rates") {
      if (value != "0" && value != "1")
        return std::fprintf(stderr, "scene_campaign: --delay-rates must be 0 or 1\n"), false;
      a->delay_rates = value == "1" ? 1 : 0;
    } else if (flag == "--closure") {
      if (value != "0" && value != "1")
        return std::fprintf(stderr, "scene_campaign: --closure must be 0 or 1\n"), false;
      a->closure = value == "1" ? 1 : 0;
    } else if (flag == "--motion-blur") {
      a->motion_blur = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(a->motion_blur >= 0.0 && a->motion_blur <= 1.0))
        return std::fprintf(stderr, "scene_campaign: --motion-blur must be in [0, 1]\n"), false;
    } else if (flag == "--fusion") {
      if (value != "0" && value != "1") return std::fprintf(stderr, "scene_campaign: --fusion must be 0 or 1\n"), false;
      a->fusion = value == "1" ? 1 : 0;
    } else if (flag == "--cross-pairs") {
      a->cross_pairs_max_sensors = static_cast<int>(std::strtol(value.c_str(), &end, 10));
      if (*end != '\0' || a->cross_pairs_max_sensors < 0 || a->cross_pairs_max_sensors > 16)
        return std::fprintf(stderr, "scene_campaign: --cross-pairs must be in [0, 16]\n"), false;
    } else if (flag == "--jobs") {
      a->jobs = static_cast<int>(std::strtol(value.c_str(), &end, 10));
      if (*end != '\0' || a->jobs < 1) return std::fprintf(stderr, "scene_campaign: --jobs must be >= 1\n"), false;
    } else {
      std::fprintf(stderr, "scene_campaign: unknown flag %s (see --help)\n", flag.c_str());
      return false;
    }
  }
  return true;
}

std::string Num(double v, const char* format = "%.3g") {
  if (std::isnan(v)) return "-";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char text[32];
  std::snprintf(text, sizeof text, format, v);
  return text;
}

// JSON numbers: non-finite values as null.
std::string JsonNum(double v) {
  if (!std::isfinite(v)) return "null";
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

void PrintRow(FILE* out, const SceneRow& r) {
  const SceneScore& s = r.score;
  if (!r.error.empty()) {
    std::fprintf(out, "%10" PRIu64 " %-9s ERROR %s\n", r.seed, SceneClassName(r.scene_class), r.error.c_str());
    return;
  }
  std::fprintf(out, "%10" PRIu64 " %-9s %-3s %-3s %-3s %4d %6s %7s %4d %8s %8s %9s %9s %8s %6d %6s %6.1f  %s\n", r.seed,
               SceneClassName(r.scene_class), s.acquired ? "yes" : "no", s.acquired_bearing ? "yes" : "no",
               s.acquired_reported ? "yes" : "no", s.far_field_frames, Num(s.range_apertures_median, "%.2f").c_str(),
               Num(s.time_to_acquire_s, "%.2f").c_str(), s.initialised_frames, Num(s.crlb_median_m).c_str(),
               Num(s.crlb_theory_median_m).c_str(), Num(s.rmse_over_crlb).c_str(), Num(s.rmse_over_crlb_theory).c_str(),
               Num(s.median_nees_per_dim).c_str(), s.lost_frames, Num(s.silent_failure_s, "%.1f").c_str(), r.wall_s,
               r.description.c_str());
}

void WriteJson(const std::string& path, const Args& a, const CampaignSummary& s) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    const std::string reason = std::generic_category().message(errno);
    std::fprintf(stderr, "scene_campaign: cannot write %s: %s\n", path.c_str(), reason.c_str());
    return;
  }
  std::fprintf(f, "{\n  \"command\": {\"scenes\": %d, \"seed\": %" PRIu64 ", \"class\": %s, \"duration_s\": %s},\n",
               a.scenes, a.seed, JsonString(a.scene_class ? SceneClassName(*a.scene_class) : "all").c_str(),
               JsonNum(a.duration_s).c_str());
  std::fprintf(f,
               "  \"summary\": {\"scenes\": %d, \"run_errors\": %d, \"acquired\": %d, \"lost\": %d, "
               "\"silent_failures\": %d, \"acquired_theory\": %d, \"acquired_bearing\": %d, "
               "\"acquired_bearing_not_position\": %d, \"acquired_reported\": %d, \"silent_failures_reported\": %d, "
               "\"range_withheld\": %d, \"median_time_to_acquire_reported_s\": %s, "
               "\"p95_time_to_acquire_reported_s\": %s, \"median_time_to_acquire_s\": %s, "
               "\"p95_time_to_acquire_s\": %s, "
               "\"median_time_to_acquire_acquired_s\": %s, \"p95_time_to_acquire_acquired_s\": %s, "
               "\"median_rmse_over_crlb_gaussian\": %s, \"median_rmse_over_crlb_hard\": %s, "
               "\"median_nees_per_dim\": %s, \"median_rmse_over_crlb_theory\": %s, \"median_error_m\": %s},\n"
               "  \"scenes\": [\n",
               s.scenes, s.run_errors, s.acquired, s.lost, s.silent_failures, s.acquired_theory, s.acquired_bearing,
               s.acquired_bearing_not_position, s.acquired_reported, s.silent_failures_reported, s.range_withheld,
               JsonNum(s.median_time_to_acquire_reported_s).c_str(), JsonNum(s.p95_time_to_acquire_reported_s).c_str(),
               JsonNum(s.median_time_to_acquire_s).c_str(), JsonNum(s.p95_time_to_acquire_s).c_str(),
               JsonNum(s.median_time_to_acquire_acquired_s).c_str(), JsonNum(s.p95_time_to_acquire_acquired_s).c_str(),
               JsonNum(s.median_rmse_over_crlb_gaussian).c_str(), JsonNum(s.median_rmse_over_crlb_hard).c_str(),
               JsonNum(s.median_nees_per_dim).c_str(), JsonNum(s.median_rmse_over_crlb_theory).c_str(),
               JsonNum(s.median_error_m).c_str());
  for (size_t i = 0; i < s.rows.size(); ++i) {
    const SceneRow& r = s.rows[i];
    const SceneScore& c = r.score;
    std::fprintf(
        f,
        "    {\"seed\": %" PRIu64
        ", \"class\": %s, \"description\": %s, \"error\": %s, \"frames\": %d, "
        "\"initialised_frames\": %d, \"acquired\": %s, \"acquired_bearing\": %s, \"acquired_reported\": %s, "
        "\"far_field_frames\": %d, \"range_withheld_s\": %s, \"time_to_acquire_reported_s\": %s, "
        "\"range_apertures_median\": %s, "
        "\"time_to_acquire_s\": %s, \"time_to_acquire_theory_s\": %s, "
        "\"crlb_median_m\": %s, "
        "\"crlb_theory_median_m\": %s, \"rmse_over_crlb\": %s, \"rmse_over_crlb_theory\": %s, \"median_error_m\": %s, "
        "\"median_nees_per_dim\": %s, \"lost_frames\": %d, \"silent_failure_s\": %s, "
        "\"silent_failure\": %s, \"silent_failure_reported_s\": %s, \"silent_failure_reported\": %s, "
        "\"wall_s\": %s}%s\n",
        r.seed, JsonString(SceneClassName(r.scene_class)).c_str(), JsonString(r.description).c_str(),
        JsonString(r.error).c_str(), c.frames, c.initialised_frames, c.acquired ? "true" : "false",
        c.acquired_bearing ? "true" : "false", c.acquired_reported ? "true" : "false", c.far_field_frames,
        JsonNum(c.range_withheld_s).c_str(), JsonNum(c.time_to_acquire_reported_s).c_str(),
        JsonNum(c.range_apertures_median).c_str(), JsonNum(c.time_to_acquire_s).c_str(),
        JsonNum(c.time_to_acquire_theory_s).c_str(), JsonNum(c.crlb_median_m).c_str(),
        JsonNum(c.crlb_theory_median_m).c_str(), JsonNum(c.rmse_over_crlb).c_str(),
        JsonNum(c.rmse_over_crlb_theory).c_str(), JsonNum(c.median_error_m).c_str(),
        JsonNum(c.median_nees_per_dim).c_str(), c.lost_frames, JsonNum(c.silent_failure_s).c_str(),
        c.silent_failure ? "true" : "false", JsonNum(c.silent_failure_reported_s).c_str(),
        c.silent_failure_reported ? "true" : "false", JsonNum(r.wall_s).c_str(), i + 1 < s.rows.size() ? "," : "");
  }
  std::fprintf(f, "  ]\n}\n");
  std::fclose(f);
}

void PrintClass(const char* name, const ClassSummary& c) {
  std::printf("  %-9s scenes %3d  acquired %3d  median RMSE/CRLB %s\n", name, c.scenes, c.acquired,
              Num(c.median_rmse_over_crlb).c_str());
}

int Trace(uint64_t seed, const RandomSceneOptions& scene_options, const Args& a) {
  const SceneRow row =
      RunRandomScene(seed, scene_options, {}, true, [&](AudioSessionConfig* c) { Adjust(a, scene_options, c); });
  if (!row.error.empty()) {
    std::fprintf(stderr, "scene_campaign: scene %" PRIu64 ": %s\n", seed, row.error.c_str());
    return 1;
  }
  const std::vector<double>& sigma_s = row.score.tdoa_sigma_robust_s;
  std::printf("%s\nrobust TDOA sigma per pair (us):", row.description.c_str());
  for (double s : sigma_s) std::printf(" %.3g", 1e6 * s);
  std::printf("\n%8s %4s %4s %4s %4s %6s %8s %9s %10s %10s %9s %9s %10s %10s %5s %7s %9s  %s\n", "t_s", "init", "pres",
              "amb", "far", "silent", "range_m", "r_err_m", "error_m", "crlb_m", "err/crlb", "brg/crlb", "sd_m", "nees",
              "pairs", "nis", "sigma_us", "per pair (measured - true) / sigma");
  for (const FrameScore& f : row.score.per_frame) {
    std::printf("%8.3f %4d %4d %4d %4d %6d %8s %9s %10s %10s %9s %9s %10s %10s %5d %7.3g %9.3g ", f.t_s, f.initialised,
                f.present, f.ambiguous, f.far_field, f.silent, Num(f.range_m, "%.4g").c_str(),
                Num(f.range_error_m, "%.3g").c_str(), Num(f.error_m, "%.4g").c_str(), Num(f.crlb_m, "%.4g").c_str(),
                Num(f.error_m / f.crlb_m).c_str(), Num(f.bearing_error_rad / f.bearing_crlb_rad).c_str(),
                Num(f.sd_m, "%.4g").c_str(), Num(f.nees_position).c_str(), f.pairs_used, f.nis, 1e6 * f.tdoa_sigma_s);
    for (size_t p = 0; p < f.tdoa_error_s.size() && p < sigma_s.size(); ++p) {
      std::printf(" %s", Num(f.tdoa_error_s[p] / sigma_s[p], "%.1f").c_str());
    }
    std::printf("\n");
  }
  PrintRow(stdout, row);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  if (!ParseArgs(argc, argv, &a)) {
    Usage(stderr);
    return 2;
  }
  if (a.help) {
    Usage(stdout);
    return 0;
  }
  RandomSceneOptions scene_options;
  scene_options.duration_s = a.duration_s;
  scene_options.scene_class = a.scene_class;
  if (a.trace_seed) return Trace(*a.trace_seed, scene_options, a);
  std::vector<SceneRow> rows(static_cast<size_t>(a.scenes));
  std::atomic<int> next{0};
  std::mutex print_mutex;
  int done = 0;
  auto worker = [&] {
    for (int i = next++; i < a.scenes; i = next++) {
      const uint64_t seed = a.seed * 1000000ULL + static_cast<uint64_t>(i);
      rows[static_cast<size_t>(i)] =
          RunRandomScene(seed, scene_options, {}, false, [&](AudioSessionConfig* c) { Adjust(a, scene_options, c); });
      const std::lock_guard<std::mutex> lock(print_mutex);
      std::fprintf(stderr, "[%d/%d] ", ++done, a.scenes);
      PrintRow(stderr, rows[static_cast<size_t>(i)]);
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < a.jobs; ++j) threads.emplace_back(worker);
  for (std::thread& t : threads) t.join();

  const CampaignSummary s = SummariseCampaign(rows);
  std::printf("%10s %-9s %-3s %-3s %-3s %4s %6s %7s %4s %8s %8s %9s %9s %8s %6s %6s %6s  %s\n", "seed", "class", "acq",
              "brg", "rep", "far", "r_aper", "t_acq_s", "init", "crlb_m", "crlb_th_m", "rmse/crlb", "rmse/crth",
              "nees/dim", "lost", "silent", "wall_s", "scene");
  for (const SceneRow& r : s.rows) PrintRow(stdout, r);
  std::printf("\nscenes %d (run errors %d), duration %g s, campaign seed %" PRIu64 "\n", s.scenes, s.run_errors,
              a.duration_s, a.seed);
  std::printf("acquired %d / %d; scenes with lost frames %d; silent failures %d\n", s.acquired, s.scenes - s.run_errors,
              s.lost, s.silent_failures);
  std::printf(
      "acquired in bearing from the centroid (3 x its CRLB): %d; of them not in position %d (%d with the "
      "source beyond 3 apertures)\n",
      s.acquired_bearing, s.acquired_bearing_not_position, s.acquired_bearing_not_position_far);
  std::printf(
      "as reported (far-field frames in bearing, the others in position): acquired %d, silent failures %d, "
      "scenes withholding an observable range > 1 s %d; time to acquire (never = inf) median %s s, p95 %s s\n",
      s.acquired_reported, s.silent_failures_reported, s.range_withheld,
      Num(s.median_time_to_acquire_reported_s, "%.2f").c_str(), Num(s.p95_time_to_acquire_reported_s, "%.2f").c_str());
  std::printf("acquired against 3 x the theoretical CRLB: %d; median time (never = inf) %s s\n", s.acquired_theory,
              Num(s.median_time_to_acquire_theory_s, "%.2f").c_str());
  std::printf("time to acquire, all scenes (never = inf): median %s s, p95 %s s\n",
              Num(s.median_time_to_acquire_s, "%.2f").c_str(), Num(s.p95_time_to_acquire_s, "%.2f").c_str());
  std::printf("time to acquire, acquired scenes: median %s s, p95 %s s\n",
              Num(s.median_time_to_acquire_acquired_s, "%.2f").c_str(),
              Num(s.p95_time_to_acquire_acquired_s, "%.2f").c_str());
  std::printf("median RMSE/CRLB after acquisition: gaussian %s, multipath+impulsive %s\n",
              Num(s.median_rmse_over_crlb_gaussian).c_str(), Num(s.median_rmse_over_crlb_hard).c_str());
  PrintClass("gaussian", s.gaussian);
  PrintClass("multipath", s.multipath);
  PrintClass("impulsive", s.impulsive);
  std::printf("median NEES per dimension (position) after acquisition: %s\n", Num(s.median_nees_per_dim).c_str());
  std::printf("median RMSE / theoretical CRLB (Knapp-Carter sigma) after acquisition: %s\n",
              Num(s.median_rmse_over_crlb_theory).c_str());
  std::printf("median position error after acquisition (median over acquired scenes): %s m\n",
              Num(s.median_error_m).c_str());
  if (!a.json_path.empty()) WriteJson(a.json_path, a, s);
  return 0;
}
