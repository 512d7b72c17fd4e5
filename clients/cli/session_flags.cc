#include "clients/cli/session_flags.h"

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace localizer::cli {

void RegisterGccFlags(FlagSet& flags, SessionFlags* f) {
  engine::AudioSessionConfig& c = f->config;
  flags.OptionalDouble("sound-speed", &f->array.sound_speed_mps, "MPS", "from the array file", "sound speed, m/s");
  flags.OptionalInt("reference", &f->array.reference_sensor, "K", "from the array file", "reference sensor index");
  flags.String("weighting", &f->weighting, "NAME",
               "GCC weighting: phat|phat-beta|scot|cc|phat-coherence|phat-share (the last two need no "
               "band: phat-coherence learns it over frames, phat-share weighs each frame's bins by "
               "their share of signal; CPU only)");
  flags.Double("phat-beta", &c.phat_beta, "B", "", "exponent of --weighting phat-beta, in [0, 1]");
  flags.Double("band-low", &c.band_low_hz, "HZ", "Hz",
               "lower edge of the GCC band (0: DC, or the array file's band_hz)");
  flags.Double("band-high", &c.band_high_hz, "HZ", "Hz",
               "upper edge of the GCC band (0: Nyquist, or the array file's band_hz)");
}

void RegisterTrackerFlags(FlagSet& flags, SessionFlags* f, const std::string& seed_flag) {
  engine::AudioSessionConfig& c = f->config;
  flags.Int("frame", &c.frame_samples, "N", "samples",
            "samples per channel per TDOA frame (sessions that list sources: about 32 ms unless given)");
  flags.Int("hop", &c.hop_samples, "N", "samples",
            "samples between frame starts (sessions that list sources: half a frame unless given)");
  flags.String("filter", &f->filter, "NAME",
               "tracker: pf (particle filter) | ekf (extended Kalman) | ukf (unscented Kalman) | "
               "mmpf (multiple-model particle filter: cv, manoeuvre, turns) | imm (interacting "
               "multiple model over --imm-modes)");
  flags.String("motion-model", &f->motion_model, "NAME",
               "ekf/ukf motion model: cv | ca | ct (coordinated turn) | singer; pf: cv");
  flags.String("imm-modes", &f->imm_modes, "LIST",
               "imm: comma-separated motion models of its modes, e.g. cv,ct | cv,ca");
  flags.String("imm-variant", &f->imm_variant, "NAME", "imm: mode filters ekf | ukf");
  flags.String("robust", &f->robust, "NAME",
               "ekf/ukf/imm update: none | huber | student-t (down-weight a pair the others contradict)");
  flags.Int("particles", &c.tracker.particle.particles, "N", "", "particle count");
  flags.String("likelihood", &f->likelihood, "NAME",
               "particle likelihood: peak (TDOA peaks, Student-t) | gcc (whole GCC functions) | "
               "mixture (Gaussian + uniform outliers)");
  flags.Double("outlier-probability", &c.tracker.particle.outlier_probability, "P", "",
               "mixture likelihood: chance that a pair's peak is an outlier, in [0, 1)");
  flags.Uint64(seed_flag, &c.seed, "S", "random seed of the particle filter");
  flags.Double("tdoa-sigma-us", &f->tdoa_sigma_us, "US", "us",
               "TDOA noise std of the peak likelihood (0: estimated online from the innovations)");
  flags.Double("accel-noise", &c.tracker.particle.accel_noise_mps2, "MPS2", "m/s^2",
               "std of the white acceleration driving the motion model, per axis");
  flags.Double("manoeuvre-share", &c.tracker.particle.manoeuvre_share, "P", "",
               "particle filter: share of the particles that manoeuvre each step, in [0, 1) (0: plain "
               "white acceleration)");
  flags.Double("manoeuvre-scale", &c.tracker.particle.manoeuvre_scale, "K", "",
               "particle filter: manoeuvring particles' acceleration std over the quiet ones', >= 1 (the "
               "mixture keeps --accel-noise as its RMS)");
  flags.Double("accel-level-floor", &c.tracker.particle.accel_level_floor, "G", "",
               "particle filter: smallest per-particle gain on --accel-noise (levels drawn log-uniform "
               "between floor and ceiling, kept by the particles the data favour; floor = ceiling = 1: "
               "one std)");
  flags.Double("accel-level-ceiling", &c.tracker.particle.accel_level_ceiling, "G", "",
               "particle filter: largest per-particle gain on --accel-noise");
  flags.Double("accel-level-switch", &c.tracker.particle.accel_level_switch_hz, "HZ", "Hz",
               "particle filter: rate at which a particle redraws its acceleration level (and its turn rate)");
  flags.Double("turn-rate-max", &c.tracker.particle.turn_rate_max_radps, "W", "rad/s",
               "particle filter: each particle turns about +z at its own rate, uniform in [-W, W] (0: off)");
  flags.Double("speed-change-max", &c.tracker.particle.speed_change_max_mps2, "A", "m/s^2",
               "particle filter: each particle speeds up or slows down along its velocity at its own rate, 0 "
               "for half of them and uniform in [-A, A] for the others (0: off; with --accel-level-floor 1 "
               "--accel-level-ceiling 1 --turn-rate-max 0: one std, the GPU filter's motion)");
  flags.String("backend", &f->backend, "NAME", "compute backend: cpu|gpu|auto (with --server: on the server)");
  flags.String("bounds-min", &f->bounds_min, "X,Y,Z",
               "lower corner of the box that can hold the source, m; per axis a number or -inf "
               "(open) (default: the array file's bounds, else open)");
  flags.String("bounds-max", &f->bounds_max, "X,Y,Z", "upper corner of that box, m; per axis a number or inf (open)");
  flags.OptionalDouble("surface-z", &f->array.surface_z_m, "Z", "from the array file, else open",
                       "water surface, m (z up): the upper z bound");
  flags.OptionalDouble("bottom-z", &f->array.bottom_z_m, "Z", "from the array file, else open",
                       "sea or lake bottom, m (z up): the lower z bound");
  flags.Double("search-radius", &c.search_radius_m, "M", "m",
               "acquisition: radius about the array centre searched for a source (0: 10 apertures)");
  flags.Double("presence-false-alarm", &c.presence_false_alarm, "P", "per frame",
               "false-alarm probability of the source-presence test, in (0, 0.1]");
  flags.Double("source-timeout", &c.source_timeout_s, "S", "s",
               "a track coasting this long with no source heard is dropped and acquisition restarts");
  flags.Double("despike-k", &c.despike_k, "K", "robust sd",
               "clip each frame's channels at K robust standard deviations before the GCC (0: off)");
  flags.Int("cross-pairs", &c.cross_pairs_max_sensors, "N", "sensors",
            "arrays of at most N sensors also measure the pairs without the reference sensor, which "
            "acquisition and presence check each position against (0: never; in [0, 16])");
  flags.Bool("no-closure", &f->no_closure,
             "do not check the reference pairs against the pairs without the reference on tracked frames "
             "(arrays of at most --cross-pairs sensors; by default a reference pair they contradict is read "
             "where they agree)");
  flags.Bool("no-fusion", &f->no_fusion,
             "do not fold the pairs without the reference into the reference pairs' delays on tracked frames "
             "(arrays of at most --cross-pairs sensors; by default each reference pair's delay is the sensors' "
             "least-squares delay over every pair's peak)");
  flags.Double("present-drop-db", &c.direction_present_drop_db, "DB", "dB",
               "direction sessions: a track is present only on frames where its peak is within DB of its "
               "own running level (when its talker stops it takes the room's weaker sound from near its "
               "direction; 0: off, the default; in [0, 60])");
  flags.Double("present-hold", &c.direction_present_hold_s, "S", "s",
               "direction sessions: a track that led its frames and misses its peak stays present for S after it "
               "was last heard (gaps between syllables; 0: present only on frames it took a peak; "
               "in [0, 1])");
  flags.Bool("no-diffuse-weighting", &f->no_diffuse,
             "direction sessions: weigh every frequency alike (by default each sensor pair's frequencies are weighted "
             "by how little a room's diffuse sound correlates across the pair: a small array otherwise hears "
             "reverberation as a source at its normal)");
  flags.String("signal-weighting", &f->signal_weighting, "on|off",
               "direction sessions: weigh each frame's frequencies by their share of signal (a talker's harmonics "
               "count, the noise and reverberation between them less), or every frequency alike (default: on for "
               "planar and volumetric arrays, off for linear ones)");
  flags.Bool("echo-test", &f->echo_test,
             "direction sessions: do not report a track whose beam holds a louder heard track's signal, "
             "delayed, and whose power rises and falls with it (a room's reflection of that source; "
             "engine/doa/echo_watch.h; default: off)");
  flags.Bool("delay-rates", &f->delay_rates,
             "where the track predicts a pair's peak to move by a sample or more within a frame (a fast "
             "source, long frames), also read the pair's channel along the predicted delay and keep the "
             "taller peak (default: off)");
  flags.String("localization", &f->localization, "NAME",
               "what is reported: position (3-D from 4+ sensors off a common plane; per source from a "
               "planar array with --source-side, or a linear one with --source-plane and --source-side) | "
               "direction (up to --max-sources sources, any array) | auto (position for a volumetric array "
               "or a linear one with --source-plane, else direction) (default: the array file's, else auto)");
  flags.OptionalInt("max-sources", &f->max_sources, "K", "the array file's, else 4 for directions",
                    "sources per frame, 1..16; with 2 or more a volumetric array's positions follow that "
                    "many sources (one per CSV row, each with its position) instead of one");
  flags.String("source-side", &f->source_side, "X,Y,Z",
               "planar and linear arrays: the sources lie where (p - array centre) . (X,Y,Z) > 0 "
               "(default: the array file's source_side, else not stated: mirror images)");
  flags.String("source-plane", &f->source_plane, "PX,PY,PZ,NX,NY,NZ",
               "linear arrays, positions: the plane holding the array and the sources, a point on it and "
               "its normal, m (default: the array file's source_plane, else none)");
}

namespace {

// The session file's keys (io/session_file.h) and the flags that override them.
const std::pair<const char*, const char*> kFlagOfKey[] = {
    {"frame_samples", "frame"},
    {"hop_samples", "hop"},
    {"weighting", "weighting"},
    {"phat_beta", "phat-beta"},
    {"band_low_hz", "band-low"},
    {"band_high_hz", "band-high"},
    {"despike_k", "despike-k"},
    {"filter", "filter"},
    {"motion_model", "motion-model"},
    {"imm_modes", "imm-modes"},
    {"imm_variant", "imm-variant"},
    {"robust", "robust"},
    {"particles", "particles"},
    {"likelihood", "likelihood"},
    {"outlier_probability", "outlier-probability"},
    {"tdoa_sigma_s", "tdoa-sigma-us"},
    {"accel_noise_mps2", "accel-noise"},
    {"manoeuvre_share", "manoeuvre-share"},
    {"manoeuvre_scale", "manoeuvre-scale"},
    {"accel_level_floor", "accel-level-floor"},
    {"accel_level_ceiling", "accel-level-ceiling"},
    {"accel_level_switch_hz", "accel-level-switch"},
    {"turn_rate_max_radps", "turn-rate-max"},
    {"speed_change_max_mps2", "speed-change-max"},
    {"seed", "filter-seed"},
    {"search_radius_m", "search-radius"},
    {"presence_false_alarm", "presence-false-alarm"},
    {"source_timeout_s", "source-timeout"},
    {"backend", "backend"},
    {"direction_present_hold_s", "present-hold"},
    {"direction_diffuse_weighting", "no-diffuse-weighting"},
    {"direction_signal_weighting", "signal-weighting"},
};

// "a,b,c" -> {"a", "b", "c"} (empty parts kept: "1,,2" has three).
std::vector<std::string> SplitCommas(const std::string& text) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (true) {
    const size_t comma = text.find(',', start);
    parts.push_back(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) return parts;
    start = comma + 1;
  }
}

}  // namespace

// --source-plane: six finite numbers, the normal not zero.
StatusOr<std::pair<engine::Vec3, engine::Vec3>> ParseSourcePlane(const std::string& text) {
  const Status refused = InvalidArgument("--source-plane is \"" + text +
                                         "\"; expected PX,PY,PZ,NX,NY,NZ (a point and the normal, finite, the "
                                         "normal not zero)");
  const std::vector<std::string> parts = SplitCommas(text);
  if (parts.size() != 6) return refused;
  double values[6];
  for (size_t k = 0; k < 6; ++k) {
    auto v = ParseFiniteDouble(parts[k]);
    if (!v.ok()) return refused;
    values[k] = *v;
  }
  const engine::Vec3 point(values[0], values[1], values[2]), normal(values[3], values[4], values[5]);
  if (normal.isZero()) return refused;
  return std::make_pair(point, normal);
}

StatusOr<engine::Vec3> ParseBoundsFlag(const std::string& flag, const std::string& text, bool is_min) {
  const std::string open = is_min ? "-inf" : "inf";
  const std::vector<std::string> parts = SplitCommas(text);
  if (parts.size() != 3) {
    return InvalidArgument("--" + flag + " is \"" + text + "\"; expected X,Y,Z (a number or " + open + " per axis)");
  }
  engine::Vec3 v;
  const char* axes = "xyz";
  for (int axis = 0; axis < 3; ++axis) {
    const std::string& part = parts[static_cast<size_t>(axis)];
    if (part == open || (!is_min && part == "+inf")) {
      v[axis] = is_min ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
      continue;
    }
    auto x = ParseFiniteDouble(part);
    if (!x.ok()) {
      return InvalidArgument("--" + flag + ": " + std::string(1, axes[axis]) + " is \"" + part +
                             "\"; expected a number or " + open + " (open)");
    }
    v[axis] = *x;
  }
  return v;
}

std::string FlagOfSessionKey(const std::string& key) {
  for (const auto& [k, flag] : kFlagOfKey) {
    if (key == k) return flag;
  }
  return "";
}

StatusOr<engine::AudioSessionConfig> BuildSessionConfig(const SessionFlags& f, const FlagSet& flags,
                                                        const io::ArrayFile& array, double sample_rate_hz, Runs runs,
                                                        std::unique_ptr<engine::Session>* checked) {
  const auto given = [&](const std::string& flag) { return flags.seen(flag) || f.also_given.contains(flag); };
  engine::AudioSessionConfig base = f.config;
  auto weighting = engine::ParseWeighting(f.weighting);
  if (!weighting.ok()) return InvalidArgument("--weighting: " + weighting.status().message());
  base.weighting = *weighting;
  engine::TrackerOptions& tracker = base.tracker;
  auto likelihood = engine::ParseLikelihood(f.likelihood);
  if (!likelihood.ok()) return InvalidArgument("--likelihood: " + likelihood.status().message());
  tracker.particle.likelihood = *likelihood;
  // Divided, not multiplied by 1e-6: 25 / 1e6 is the double nearest 2.5e-05, as the session
  // file's tdoa_sigma_s and localizer.engine's are (25 * 1e-6 is one ulp below).
  tracker.particle.tdoa_sigma_s = f.tdoa_sigma_us / 1e6;
  auto filter = engine::ParseFilterKind(f.filter, "filter");
  if (!filter.ok()) return filter.status();
  tracker.kind = *filter;
  auto motion_model = engine::ParseMotionModelKind(f.motion_model, "motion_model");
  if (!motion_model.ok()) return motion_model.status();
  tracker.kalman.motion_model = *motion_model;
  auto imm_variant = engine::ParseKalmanVariant(f.imm_variant, "imm_variant");
  if (!imm_variant.ok()) return imm_variant.status();
  tracker.imm_variant = *imm_variant;
  auto robust = engine::ParseRobustUpdate(f.robust, "robust");
  if (!robust.ok()) return robust.status();
  tracker.kalman.robust = *robust;
  auto imm_modes = engine::ParseImmModes(f.imm_modes, "imm_modes");
  if (!imm_modes.ok()) return imm_modes.status();
  tracker.imm_modes = *std::move(imm_modes);
  auto backend = engine::ParseBackendChoice(f.backend, "backend");
  if (!backend.ok()) return backend.status();
  base.backend = *backend;
  if (f.delay_rates) base.delay_rate_compensation = true;
  if (f.no_closure) base.pair_closure = false;
  if (f.no_fusion) base.pair_fusion = false;
  if (f.no_diffuse) base.direction_diffuse_weighting = false;
  if (!f.signal_weighting.empty()) {
    if (f.signal_weighting != "on" && f.signal_weighting != "off")
      return InvalidArgument("--signal-weighting is '" + f.signal_weighting + "'; give on or off");
    base.direction_signal_weighting = f.signal_weighting == "on";
  }
  if (f.echo_test) base.direction_echo_test = true;
  // The session file's settings where no flag was given: where the flag would have put them,
  // before the couplings below, so that a setting means the same from either.
  io::ApplySessionSettings(
      array.session, [&](const std::string& key) { return given(FlagOfSessionKey(key)); }, &base);
  // One motion and TDOA noise for every filter (--accel-noise, --tdoa-sigma-us).
  tracker.kalman.motion.accel_noise_mps2 = tracker.particle.accel_noise_mps2;
  tracker.kalman.tdoa_sigma_s = tracker.particle.tdoa_sigma_s;
  tracker.kalman.min_peak_snr = tracker.particle.min_peak_snr;
  io::ArrayOverrides overrides = f.array;
  if (!f.bounds_min.empty()) {
    auto v = ParseBoundsFlag("bounds-min", f.bounds_min, true);
    if (!v.ok()) return v.status();
    if (f.array.bottom_z_m && std::isfinite(v->z())) {
      return InvalidArgument("--bottom-z and the z of --bounds-min both give the lower z bound; keep one");
    }
    overrides.bounds_min_m = *v;
  }
  if (!f.bounds_max.empty()) {
    auto v = ParseBoundsFlag("bounds-max", f.bounds_max, false);
    if (!v.ok()) return v.status();
    if (f.array.surface_z_m && std::isfinite(v->z())) {
      return InvalidArgument("--surface-z and the z of --bounds-max both give the upper z bound; keep one");
    }
    overrides.bounds_max_m = *v;
  }
  engine::AudioSessionConfig config = io::TrackConfigFor(std::move(base), array, overrides, sample_rate_hz);
  if (!f.localization.empty()) {
    auto localization = engine::ParseLocalization(f.localization, "--localization");
    if (!localization.ok()) return localization.status();
    config.localization = *localization;
  }
  if (f.max_sources) config.max_sources = *f.max_sources;
  if (!f.source_side.empty()) {
    auto side = ParseBoundsFlag("source-side", f.source_side, true);
    if (!side.ok() || !side->allFinite() || side->isZero()) {
      return InvalidArgument("--source-side is \"" + f.source_side + "\"; expected X,Y,Z, finite and not all zero");
    }
    config.source_side = *side;
  }
  if (!f.source_plane.empty()) {
    auto plane = ParseSourcePlane(f.source_plane);
    if (!plane.ok()) return plane.status();
    config.source_plane_point_m = plane->first;
    config.source_plane_normal = plane->second;
  }
  for (int axis = 0; axis < 3; ++axis) {
    if (!(config.bounds_min_m[axis] < config.bounds_max_m[axis])) {
      const char* names[3] = {"x", "y", "z"};
      return InvalidArgument(std::string("bounds: ") + names[axis] + " min " + FormatDouble(config.bounds_min_m[axis]) +
                             " is not below max " + FormatDouble(config.bounds_max_m[axis]) +
                             " (--bounds-min/--bounds-max, --bottom-z/--surface-z, or the array file)");
    }
  }
  auto sources = engine::ReportsSources(config);
  const bool frame_given = given("frame") || array.session.frame_samples;
  const bool hop_given = given("hop") || array.session.hop_samples;
  if (sources.ok() && *sources && !frame_given) {
    const double frame = std::exp2(std::round(std::log2(std::max(64.0, 0.032 * config.sample_rate_hz))));
    config.frame_samples = static_cast<int>(std::min(frame, double{1 << 20}));
    if (!hop_given) config.hop_samples = config.frame_samples / 2;
  }
  if (runs == Runs::kOnServer) {
    // Engine-only settings the wire does not carry: a server session would silently run
    // without them.
    for (const auto& [flag, set] : {std::pair<const char*, bool>{"echo-test", f.echo_test},
                                    {"present-drop-db", config.direction_present_drop_db != 0.0},
                                    {"no-fusion", f.no_fusion},
                                    {"no-closure", f.no_closure},
                                    {"delay-rates", f.delay_rates}}) {
      if (set) {
        return InvalidArgument(std::string("--") + flag +
                               " is not carried to a server (the wire has no such setting); run locally");
      }
    }
    // The wire reads these zeros as "the server's default" (wire/config_wire.cc), so a 0 asked
    // for here would silently become the default there: refused instead.
    for (const auto& [flag, value] :
         {std::pair<const char*, double>{"accel-noise", config.tracker.particle.accel_noise_mps2},
          {"phat-beta", config.phat_beta},
          {"outlier-probability", config.tracker.particle.outlier_probability}}) {
      if (value == 0.0) {
        return InvalidArgument(std::string("--") + flag +
                               " 0 (or its array-file key) cannot be sent to a server: the " +
                               "wire reads 0 as the server's default; give a small positive value, or run locally");
      }
    }
  }
  engine::AudioSessionConfig check = config;
  if (runs == Runs::kOnServer) check.backend = engine::BackendChoice::kCpu;
  // Create, not just Validate: some limits (band edges against Nyquist, the backend) are
  // only checked when the stages are built, and a bad flag should fail here as a usage error.
  auto session = engine::Session::Create(check);
  if (!session.ok()) return session.status();
  if (checked != nullptr && runs == Runs::kLocally) *checked = std::move(*session);
  return config;
}

}  // namespace localizer::cli
