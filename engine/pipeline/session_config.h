// What a session is opened with: one config type per kind of session.
//
//   AudioSessionConfig      an audio session (session.h): a sensor array's samples in, one
//                           tracked source out (fixed or moving array).
//   DetectionSessionConfig  a detection session (scan_session.h): scans of plots from a
//                           detecting sensor in, many target tracks out.
//   SessionConfig           either of them: what the wire codec (wire/config_wire.h) decodes
//                           and what the server's session factory opens. Only the codec and
//                           that factory look at which kind it holds; the engine's sessions
//                           each take their own kind.
// Each kind's config holds everything its session reads (Session::Create and
// ScanSession::Create take one argument), so SessionConfig is the variant alone: the fields
// both kinds have (the seed) live in each.
//
// Every choice among named alternatives is an enum here (FilterKind, MotionModelKind,
// KalmanVariant, RobustUpdate, BackendChoice, Weighting, ...); their names are parsed once,
// at the edge (the proto codec, the CLI flags), by the Parse…(name, field) next to each
// enum. Validate() checks what a type cannot: numeric ranges and the fields that depend on
// each other.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "engine/attitude/attitude_filter.h"
#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/pipeline/backend.h"
#include "engine/tdoa/gcc_phat.h"
#include "engine/tws/tws_options.h"

namespace localizer::engine {

// What an audio session reports (issue 18): positions, or the directions of up to
// max_sources sources (any array of two or more sensors; a planar array's direction has a
// mirror image across its plane unless source_side is stated, a linear array's is a cone
// angle). Positions:
//   volumetric (4 or more sensors off a common plane): the tracker's 3-D position, each
//     estimate saying (Estimate::far_field) whether its frame bounds the range;
//   planar (4 or more sensors), with source_side: each source's 3-D position on that side;
//   linear (3 or more sensors), with source_plane (a plane holding the array and the
//     sources) and source_side (which side of the array in that plane): 2-D positions;
// the last two follow sources by direction (Estimate::sources) and give each a position
// where the frame bounds its range (engine/doa/near_field.h), the direction otherwise. So
// does a volumetric array whose config states max_sources >= 2: several sources, each with
// its own track and 3-D position (no side needed), in place of the one-source tracker.
// auto: position for a volumetric array and for a linear one with source_plane stated,
// direction otherwise (a planar array's source_side also serves directions: ask for
// position to have its near-field positions).
enum class Localization { kAuto, kPosition, kDirection };
// "auto" | "position" | "direction"; INVALID_ARGUMENT naming `field` otherwise.
StatusOr<Localization> ParseLocalization(const std::string& name, const std::string& field);
const char* LocalizationName(Localization l);

struct AudioSessionConfig {
  // Array
  std::vector<Vec3> sensors_m;      // >= 2 (positions: above)
  double sound_speed_mps = 1500.0;  // > 0 (1500 water, 343 air)
  int reference_sensor = 0;
  double sample_rate_hz = 0.0;  // > 0
  // What the session reports (above) and how many sources per frame, in [0, 16]: 0 (not
  // stated) is 4 for sessions that follow sources by direction, and one source with the
  // tracker for a volumetric array's positions; stated as 2 or more, a volumetric array's
  // positions follow that many sources by direction, each with a near-field position
  // (EffectiveMaxSources()). And on which side of a planar array the sources lie: where
  // (p - centroid).source_side > 0 (zero: not stated; then each direction has a mirror).
  Localization localization = Localization::kAuto;
  int max_sources = 0;
  Vec3 source_side = Vec3::Zero();
  // Linear arrays, positions: the plane holding the array and the sources, a point on it and
  // its normal (zero normal: not stated).
  Vec3 source_plane_point_m = Vec3::Zero();
  Vec3 source_plane_normal = Vec3::Zero();
  // Framing
  int frame_samples = 4096;             // per channel, in [64, 1 << 20]
  int hop_samples = 2048;               // in [1, frame_samples]
  int64_t max_block_samples = 1 << 22;  // per channel per block
  // TDOA front end (engine/tdoa/gcc_phat.h; GccOptionsFor() adds the framing and the
  // sample rate)
  Weighting weighting = Weighting::kPhat;
  double phat_beta = 0.8;
  double band_low_hz = 0.0;
  double band_high_hz = 0.0;  // 0: Nyquist
  // Arrays of at most this many sensors (in [0, 16]; 0: never) also measure the pairs without
  // the reference (GccOptions::cross_pairs_max_sensors): acquisition and presence check every
  // position against them (a 4-sensor array's three reference pairs cannot outvote one that
  // locked on an echo or a noise peak), and tracked frames fold them into the reference pairs'
  // delays (pair_fusion). 8 since the fusion (ACCURACY.md, "Twenty-eighth pass"): every pair
  // costs +40 % of the pipeline at 6 sensors and +70 % at 8 (BENCHMARKS.md).
  int cross_pairs_max_sensors = 8;
  // true: on such arrays every tracked frame also measures the pairs without the reference,
  // and a reference pair whose peak they contradict is measured where they agree
  // (pair_closure.h): a 4-sensor array's track cannot otherwise see one pair locked on an echo.
  bool pair_closure = true;
  // true: on such arrays every tracked frame folds the cross pairs' peaks into the reference
  // pairs' delays, after the closure check: each becomes the sensors' least-squares delay over
  // every pair, with its sigma (pair_fusion.h). The filters then read M (M - 1) / 2 pairs'
  // evidence through M - 1 delays. Estimate::delay_s keeps the reference pairs' own peaks.
  bool pair_fusion = true;
  // true: a track's predicted delay rates (one hypothesis, a fixed array) are handed to the
  // front end (TdoaEstimator::SetDelayRates, delay_warp.h) on frames where some pair's peak
  // would otherwise move by a sample or more: a fast source near the array, whose peak smears
  // over a long frame. Each such pair is also measured with its sensor's channel read along the
  // predicted delay, and keeps the taller peak. Off by default: twenty campaign draws at 4096
  // frames were unchanged within their scatter (silent failures 1 -> 3, absolute error x 1.00),
  // and at the campaign's quarter-second frames the error fell by 2.5 % with silent failures
  // 11 -> 13 (ACCURACY.md, twenty-third pass). For long frames and fast sources.
  bool delay_rate_compensation = false;
  // Impulsive-noise front end (engine/tdoa/despike.h): each frame's channels are clipped at
  // despike_k robust standard deviations before the GCC (0: off), keeping outliers that every
  // channel shows within the array's largest delay (a coherent impulsive source).
  double despike_k = 5.0;
  // Tracker: its kind and each filter's own options (backend.h). The particle filters'
  // seed is `seed` below. Only ekf and ukf take a motion model other than cv (pf and mmpf
  // set their own models, imm takes imm_modes). The wire carries the options the proto's
  // FilterConfig names; a session opened on a server has the defaults for the others.
  TrackerOptions tracker;
  // Former single-fix initialisation; kept for the wire contract, unused since acquisition
  // (engine/acquisition) initialises from every mode the data allows.
  double min_pair_quality = 1.5;
  double max_fix_std_m = 0.0;
  double init_speed_sigma_mps = 2.0;  // velocity spread at initialisation
  // A region known to hold the source: when min <= max (all finite), the tracker starts
  // from it at the first frame instead of waiting for a good fix. Unset by default.
  Vec3 init_region_min_m = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  Vec3 init_region_max_m = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  int divergence_window = 8;  // frames averaged by the divergence test
  // Physical bounds on the source position: a box whose sides may be infinite (unbounded;
  // the default on every side). Particles, fixes and acquisition candidates outside it are
  // impossible. A water column: bounds_max_m.z() = the surface, bounds_min_m.z() = the bottom.
  Vec3 bounds_min_m = Vec3::Constant(-std::numeric_limits<double>::infinity());
  Vec3 bounds_max_m = Vec3::Constant(std::numeric_limits<double>::infinity());
  // Acquisition (engine/acquisition): the volume searched for a source when there is no
  // trustworthy track, a sphere of this radius about the array centre intersected with the
  // bounds (0: 10 apertures).
  double search_radius_m = 0.0;
  // Source presence: the per-frame false-alarm probability the presence test is set for,
  // in (0, 0.1]; and how long a track coasts with no source heard before it is dropped and
  // acquisition restarts (> 0).
  double presence_false_alarm = 1e-3;
  double source_timeout_s = 2.0;
  // Direction sessions' search and tracker, engine-only tuning (not on the wire or the CLI):
  // SrpOptions::search_starts, in [1, 64], and DirectionTrackerOptions::co_lead_share, in
  // [0, 1]. Both measured in ACCURACY.md ("Large arrays and several sources") with
  // tests/bench/two_source_report; the defaults keep each off.
  int direction_search_starts = 1;
  double direction_co_lead_share = 0.0;
  // Direction sessions: a track whose beam carries another heard track's signal delayed (a
  // room's reflection of that source: engine/doa/echo_watch.h) is not reported. Off by
  // default (measured in ACCURACY.md, "Reflections heard as sources"); `track --echo-test`.
  bool direction_echo_test = false;
  // Direction sessions: a track is reported present (source_present) only on frames where the
  // peak it took is within this many dB of its own running level (0: off, in [0, 60]). When a
  // talker stops, its track goes on taking what the room brings from near its direction (the
  // other talkers' reflections), far weaker: on seeded rooms that "lingering" time was 1.9-2.8 s
  // per minute on the 4-microphone square and 12-13 on the 8-microphone line. Off by default
  // (ACCURACY.md, "A track's own level"); `track --present-drop-db DB`.
  double direction_present_drop_db = 0.0;
  // Direction sessions: a confirmed track that misses its peak (coasting) stays present for
  // this long after it was last heard (s, in [0, 1]; 0: present only on frames it took a
  // peak), when on that frame it took the frame's strongest peak and it took a peak in 4 of the
  // last 5 frames (a track on a reflection seldom leads). Speech leaves 20-80 ms between
  // syllables and scatters single frames' peaks; a talker is there through them. Measured in
  // ACCURACY.md ("A talker between syllables"); `track --present-hold S`.
  double direction_present_hold_s = 0.05;
  // Direction sessions: each sensor pair's frequencies weighted by how little a room's diffuse
  // sound correlates across the pair (engine/doa/pair_spectra.h, "Diffuse weighting"): without
  // it a small array hears a room's reverberation as a source lifted towards its normal
  // (planar) or broadside (linear). Measured in ACCURACY.md ("The room's diffuse sound");
  // `track --no-diffuse-weighting`.
  bool direction_diffuse_weighting = true;
  // Direction sessions: each frame's frequencies weighted by their share of signal
  // (engine/doa/pair_spectra.h, "Signal weighting"): a talker's harmonics count, the noise and
  // reverberation between them less. Unset: on for planar and volumetric arrays, off for
  // linear ones (a line resolves a talker's floor and ceiling images as sources of their own,
  // and the weighting lifts them with the talker: on seeded rooms with speech, 3-6 points more
  // heard share for 2-6 s per minute more false source). Measured in ACCURACY.md ("A talker's
  // harmonics"); `track --signal-weighting on|off`.
  std::optional<bool> direction_signal_weighting;
  // Moving array (platform_pose.h): sensors_m are in the platform's body frame (the IMU's
  // axes) and the session is fed IMU samples (AddImu); each frame's TDOA model uses the
  // sensors rotated by the platform's attitude at that frame and moved to its origin.
  // Estimates carry the platform pose. The particle filter then runs on the CPU.
  bool array_in_body_frame = false;
  AttitudeFilterOptions attitude;         // the platform's attitude filter
  Vec3 platform_origin_m = Vec3::Zero();  // body origin in the world until SetPlatformOrigin
  // Compute backend (backend.h): cpu, gpu (a clear error where there is none) or auto.
  BackendChoice backend = BackendChoice::kCpu;
  uint64_t seed = 1;  // every random draw of the session (particle filters)

  // INVALID_ARGUMENT naming the field: a numeric field out of its range, a motion model
  // other than cv for a filter kind other than ekf and ukf, the particle options (checked
  // whatever the kind), the attitude options of a moving array.
  Status Validate() const;
  // max_sources, or 4 where it is not stated (0).
  int EffectiveMaxSources() const { return max_sources > 0 ? max_sources : kDefaultMaxSources; }
  static constexpr int kDefaultMaxSources = 4;
  // The TDOA front end's options: frame length, sample rate, weighting, band, the frames'
  // taper (FramingTaperFraction below); the GCC function is kept (acquisition, presence and
  // multipath association read it).
  GccOptions GccOptionsFor() const;
};

// The frames' taper for a framing (GccOptions::taper_fraction): the widest Tukey window
// whose copies, hop_samples apart, still sum to a constant, 2 (1 - hop / frame) clamped to
// [GccOptions' default 0.2, 1]. At the default 50 % overlap that is a Hann window: every
// sample keeps its weight across the frames that hold it, while each frame's ends no longer
// scatter its peak. A framing with little or no overlap (Locate's single frame) keeps 0.2,
// since a wider window would give up samples no other frame sees. Measured, twenty draws of
// the random campaign (ACCURACY.md, "Twenty-first pass"), taper 0.2 -> Hann: acquired 3945 ->
// 3960 of 4000, silent failures 24 -> 14, p95 time to acquire 6.0 / 6.3 -> 4.8 / 4.7 s and
// Gaussian RMSE/CRLB 0.549 / 0.558 -> 0.538 / 0.514 (medians of each ten draws).
double FramingTaperFraction(int frame_samples, int hop_samples);

// A detection session's config: the track-while-scan tracker's options
// (engine/tws/tws_options.h). A scan session draws nothing at random; `seed` is kept so
// that the config reports back as it was given.
struct DetectionSessionConfig {
  tws::TwsOptions tws;
  uint64_t seed = 1;

  Status Validate() const;  // INVALID_ARGUMENT naming the tracker's field (tws_options.h)
};

using SessionConfig = std::variant<AudioSessionConfig, DetectionSessionConfig>;

}  // namespace localizer::engine
