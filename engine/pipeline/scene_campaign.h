// The randomised scene campaign: one random scene (engine/sim/random_scene.h) through a
// Session configured as a user who knows only the array would configure it, scored per frame
// against the simulator's truth and the per-frame Cramer-Rao bound; and a summary over many.
//
// Scoring (ScoreScene), per frame:
//   - the true TDOA of pair k is the array's at the truth for reception time t_s - d_k / 2
//     (d_k the measured delay: the instant a pair describes, evaluation.h);
//   - sigma_k, pair k's robust measured TDOA spread: 1.4826 x the median absolute deviation of
//     (measured - true) over every frame inside the truth, so that outlier frames (ghost peaks,
//     echoes, impulses) do not inflate the bound; floored at 1e-3 sample periods;
//   - CRLB = sqrt(trace((H^T R^-1 H)^-1)) at the true position, R = diag(sigma_k^2);
//     optionally also from a theoretical sigma per pair (TheoreticalTdoaSigma);
//   - error = |estimated - true position|, position NEES = e^T P^-1 e with the estimate's 3x3
//     position covariance (infinite when P is not positive definite).
// A frame counts when it lies inside the truth and, if the engine reports presence at all
// (some frame has presence_threshold > 0), the estimate says a source is present (every
// scene has one, so a "not present" frame is a miss, not an error to score).
//   - time to acquire: the earliest instant after which every counted initialised frame has
//     error <= acquire_crlb_multiple x CRLB to the end; not acquired when there is none;
//   - after acquisition: RMSE / CRLB = sqrt(mean((error / CRLB)^2)), median position NEES / 3;
//   - lost frames: after the first counted initialised frame within acquire_crlb_multiple x
//     CRLB, those whose error exceeds lost_crlb_multiple x CRLB;
//   - bearing (what an array gives when it cannot see range, issue 18): the angle between
//     estimate - centroid and truth - centroid, against the bearing CRLB, the CRLB's position
//     covariance projected across the line of sight and divided by the range; acquired in
//     bearing like acquired in position, with the same multiple;
//   - as reported (issue 18's far field): a frame whose estimate says far_field (its range
//     unobservable) is judged in bearing where the truth's own bound agrees that the range is
//     weak (its range sd at least a sixth of the range: half the engine's kFarFieldRangeShare),
//     every other frame in position; acquired as reported like acquired in position. A frame
//     that says far field where the truth's bound is tighter withholds a range the data held:
//     it is judged in position and adds one hop to range_withheld_s;
//   - silent failure: counted frames that are initialised, not ambiguous, with error >
//     lost_crlb_multiple x CRLB and position NEES > silent_nees add one hop each; more than
//     silent_min_s of them in total is a silent failure (the tracker was badly wrong and said
//     it was sure). As reported: far-field frames count instead when the bearing error exceeds
//     lost_crlb_multiple x its bound and 3 x the estimate's own bearing sd (its covariance
//     across the line of sight over the range).
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/core/estimate.h"
#include "engine/pipeline/session.h"
#include "engine/sim/random_scene.h"
#include "engine/sim/simulator.h"

namespace localizer::engine {

struct SceneScoreOptions {
  double acquire_crlb_multiple = 3.0;
  double lost_crlb_multiple = 10.0;
  double silent_nees = 50.0;  // position NEES (3 degrees of freedom, not per dimension)
  double silent_min_s = 1.0;
};

struct FrameScore {
  double t_s = 0.0;
  bool counted = false;  // inside the truth and present (see above)
  bool initialised = false;
  double error_m = std::numeric_limits<double>::quiet_NaN();
  double crlb_m = std::numeric_limits<double>::quiet_NaN();
  double crlb_theory_m = std::numeric_limits<double>::quiet_NaN();
  double nees_position = std::numeric_limits<double>::quiet_NaN();
  double bearing_error_rad = std::numeric_limits<double>::quiet_NaN();
  double bearing_crlb_rad = std::numeric_limits<double>::quiet_NaN();
  double range_apertures = std::numeric_limits<double>::quiet_NaN();  // the truth's, from the centroid
  double range_m = std::numeric_limits<double>::quiet_NaN();          // the truth's, from the centroid
  double range_error_m = std::numeric_limits<double>::quiet_NaN();    // estimate's range - truth's (signed)
  double range_share = std::numeric_limits<double>::quiet_NaN();      // the truth's range bound / range
  bool far_field = false;                                             // the estimate's Estimate::far_field
  // What the frame is judged on as reported: bearing error and bound when far field, else
  // position error and bound.
  double reported_error = std::numeric_limits<double>::quiet_NaN();
  double reported_bound = std::numeric_limits<double>::quiet_NaN();
  double bearing_sd_rad = std::numeric_limits<double>::quiet_NaN();  // the estimate's own
  // What the estimate said of itself, for traces: sqrt(trace) of its position covariance,
  // and its presence and ambiguity flags.
  double sd_m = std::numeric_limits<double>::quiet_NaN();
  bool present = false;
  bool ambiguous = false;
  bool silent = false;  // adds to SceneScore::silent_failure_s (the rule above)
  int pairs_used = 0;
  double nis = 0.0;
  double tdoa_sigma_s = 0.0;         // the TDOA noise std the tracker assumed
  std::vector<double> tdoa_error_s;  // per pair: measured - true TDOA (NaN where not measured)
};

struct SceneScore {
  int frames = 0;
  int initialised_frames = 0;
  bool presence_reported = false;
  std::vector<double> tdoa_sigma_robust_s;                          // per pair
  std::vector<double> tdoa_sigma_theory_s;                          // per pair, as given (empty: not computed)
  double crlb_median_m = std::numeric_limits<double>::quiet_NaN();  // over counted frames
  double crlb_theory_median_m = std::numeric_limits<double>::quiet_NaN();
  bool acquired = false;
  double time_to_acquire_s = std::numeric_limits<double>::infinity();
  // The same against the theoretical CRLB: stricter where the front end's measured spread is
  // itself poor (mostly outliers inflate even the robust sigma, and with it the bound).
  bool acquired_theory = false;
  double time_to_acquire_theory_s = std::numeric_limits<double>::infinity();
  // The same for the bearing from the array's centroid (see above).
  bool acquired_bearing = false;
  double time_to_acquire_bearing_s = std::numeric_limits<double>::infinity();
  // As reported (see above).
  bool acquired_reported = false;
  double time_to_acquire_reported_s = std::numeric_limits<double>::infinity();
  int far_field_frames = 0;  // counted, initialised frames that said far field
  double range_withheld_s = 0.0;
  double silent_failure_reported_s = 0.0;
  bool silent_failure_reported = false;
  double range_apertures_median = std::numeric_limits<double>::quiet_NaN();  // the truth's, counted frames
  double rmse_over_crlb = std::numeric_limits<double>::quiet_NaN();          // after acquisition
  // The same against the theoretical per-frame CRLB (NaN without theory sigmas): shows how
  // far the measured TDOA spread itself is from what the scene's SNR and band allow.
  double rmse_over_crlb_theory = std::numeric_limits<double>::quiet_NaN();
  double median_error_m = std::numeric_limits<double>::quiet_NaN();  // after acquisition
  double median_nees_per_dim = std::numeric_limits<double>::quiet_NaN();
  double initialised_after_acquire = std::numeric_limits<double>::quiet_NaN();  // fraction
  int lost_frames = 0;
  double silent_failure_s = 0.0;
  bool silent_failure = false;
  std::vector<FrameScore> per_frame;
};

// The scorer above; a pure function of its inputs. `theory_sigma_s` (one per pair, or empty)
// adds the theoretical CRLB.
SceneScore ScoreScene(const ArrayGeometry& array, const SimResult& sim, const std::vector<Estimate>& estimates,
                      const std::vector<double>& theory_sigma_s = {}, const SceneScoreOptions& options = {});

// The TDOA CRLB of one pair for a Gaussian scene (Knapp & Carter 1976):
//     var = [2 T int (2 pi f)^2 snr_f^2 / (1 + 2 snr_f) df]^-1 over [band_low, band_high],
// snr_f the per-frequency SNR of a flat source band against white noise over [0, fs / 2]
// (equal on every channel: the simulator sets the SNR per channel), T the frame length.
// Ignores echoes and impulses; tonal scenes count their broadband share only (the tones'
// lines add little delay information per hertz and alias it); empty for click trains or no
// noise.
std::vector<double> TheoreticalTdoaSigma(const SimOptions& sim, int pair_count, int frame_samples);

// The config a user knowing only the array would give: sensors, sound speed, sample rate,
// frame 4096 / hop 2048 up to 16 kHz (frames of about the same duration above: 16384 at
// 48 kHz), no band hint, backend cpu, seed = the scene's seed; everything else default.
AudioSessionConfig CampaignSessionConfig(const RandomScene& scene);

struct SceneRow {
  uint64_t seed = 0;
  SceneClass scene_class = SceneClass::kGaussian;
  std::string description;
  std::string error;  // non-empty when the scene could not be run (and score is empty)
  SceneScore score;
  double wall_s = 0.0;
};

// Draws, simulates, tracks and scores one scene; the per-frame rows are dropped unless
// keep_frames. Errors go to SceneRow::error (a campaign keeps running). `adjust`, when set,
// changes the default config before the session is made (e.g. another weighting).
SceneRow RunRandomScene(uint64_t seed, const RandomSceneOptions& scene_options,
                        const SceneScoreOptions& score_options = {}, bool keep_frames = false,
                        const std::function<void(AudioSessionConfig*)>& adjust = {});

struct ClassSummary {
  int scenes = 0;
  int acquired = 0;
  double median_rmse_over_crlb = std::numeric_limits<double>::quiet_NaN();  // acquired scenes
};

struct CampaignSummary {
  int scenes = 0;
  int run_errors = 0;
  int acquired = 0;
  int lost = 0;  // scenes with lost frames
  int silent_failures = 0;
  int acquired_theory = 0;                    // against 3 x the theoretical CRLB
  int acquired_bearing = 0;                   // in bearing from the centroid (against its CRLB)
  int acquired_bearing_not_position = 0;      // of those, not acquired in position
  int acquired_bearing_not_position_far = 0;  // of those, the truth beyond 3 apertures (median)
  int acquired_reported = 0;                  // in what each frame reported (position, or bearing when far field)
  int silent_failures_reported = 0;           // the same, for silent failures
  int range_withheld = 0;                     // scenes with more than 1 s of range withheld (see ScoreScene)
  double median_time_to_acquire_reported_s = std::numeric_limits<double>::infinity();  // all scenes
  double p95_time_to_acquire_reported_s = std::numeric_limits<double>::infinity();
  double median_time_to_acquire_theory_s = std::numeric_limits<double>::infinity();  // all scenes
  // Over every scene run, a scene never acquired counting as +inf.
  double median_time_to_acquire_s = std::numeric_limits<double>::infinity();
  double p95_time_to_acquire_s = std::numeric_limits<double>::infinity();
  // Over acquired scenes only.
  double median_time_to_acquire_acquired_s = std::numeric_limits<double>::quiet_NaN();
  double p95_time_to_acquire_acquired_s = std::numeric_limits<double>::quiet_NaN();
  double median_rmse_over_crlb_gaussian = std::numeric_limits<double>::quiet_NaN();
  double median_rmse_over_crlb_hard = std::numeric_limits<double>::quiet_NaN();  // multipath + impulsive
  ClassSummary gaussian, multipath, impulsive;
  double median_nees_per_dim = std::numeric_limits<double>::quiet_NaN();           // acquired scenes
  double median_rmse_over_crlb_theory = std::numeric_limits<double>::quiet_NaN();  // acquired scenes
  // The median over acquired scenes of each one's median position error, m: in absolute
  // terms, beside the ratios to bounds that move with the front end's own spread.
  double median_error_m = std::numeric_limits<double>::quiet_NaN();
  std::vector<SceneRow> rows;
};

CampaignSummary SummariseCampaign(std::vector<SceneRow> rows);

// Nearest-rank quantile q in [0, 1] of finite-or-infinite values (NaN dropped); NaN if none.
double Quantile(std::vector<double> values, double q);

}  // namespace localizer::engine
