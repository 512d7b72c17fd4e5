// Bootstrap particle filter for one source tracked from TDOAs.
//
// State per particle: (x, y, z, vx, vy, vz) in m and m/s, stored as float32
// structure-of-arrays so every per-particle loop vectorises; weights in the log domain.
//
// Predict (nearly constant velocity, piecewise-constant white acceleration a ~ N(0, q I3) per
// step, Bar-Shalom's discretisation; q = accel_noise_mps2^2), the velocity mean-reverting
// with time constant tau = velocity_time_constant_s (d = exp(-dt / tau); tau = 0: d = 1):
//     p <- p + tau (1 - d) v + a dt^2 / 2,     v <- d v + a dt
// Random numbers: a counter-based generator keyed by (seed, draw number, index), so a run
// replays exactly and the loops have no sequential RNG dependency; normals by Box–Muller.
//
// Update, for each pair k whose peak_snr >= min_peak_snr (the others carry no source, so
// they are left out; with none left the update changes nothing), with measured delay d_k:
//   predicted delay at the instant the pair describes (the centre of the two windows'
//   overlap, d_k / 2 earlier than the frame centre at the reference), to first order:
//     h_k'(s) = h_k(p) - (d_k / 2) * (dh_k/dp . v)
//   peak likelihood (the seed's Gaussian made heavy-tailed): with z_k = (d_k - h_k') / sigma,
//     log w += -(nu + 1)/2 sum_k log(1 + z_k^2 / nu)        (Student-t, nu = peak_dof)
//     — near the peak it is the Gaussian; far out it still points the way (a clipped
//     Gaussian goes flat and the filter coasts), and one pair locked on a reflection
//     cannot wipe out every particle;
//   mixture likelihood (Gaussian + uniform outliers): with eps = outlier_probability and
//     W_k = 2 max_delay_s(k) the span of delays the pair can measure,
//     log w += sum_k log((1 - eps) N(z_k; 0, 1) / sigma + eps / W_k)
//     — a frame's pair is either right (Gaussian) or anywhere it can be (a reflection, a
//     second source), so an outlier costs every particle the same floor instead of
//     pulling the cloud;
//   GCC likelihood: log w += sum_k kappa_k g_k(h_k' * fs), g_k the pair's GCC over its lag
//     window (upsampled 8x by a windowed sinc, then Catmull-Rom between fine lags),
//     kappa_k = gcc_sharpness / (sigma_k^2 * -g_k'') at the highest peak (sigma in
//     samples): as sharp as the peak likelihood around the main peak, yet every other peak
//     keeps its height, so the prior chooses between them.
// sigma_k is tdoa_sigma_s when set; when 0 it is estimated online per pair from the
// innovations (Mehra's innovation-based estimate): sigma_k^2 <- (1 - a) sigma_k^2 +
// a max(0, e_k^2 - Var[h_k']) with e_k = d_k - E[h_k'] under the prior, a = 0.05, starting
// at 0.1 sample and kept within [0.01, 2] samples.
// Then log-weights are normalised (log-sum-exp), ESS = 1 / sum w^2, and when
// ESS < resample_threshold * N the particles are resampled systematically (weights reset)
// and moved by a shrunk kernel (regularised PF, Liu & West 2001; see particle_set.h) so that a likelihood far narrower
// than the prior — TDOAs are precise to centimetres — does not collapse the cloud onto a few clones for good.
//
// Cost per step: O(N * pairs), about 15 ns per particle with 3 pairs on one Zen 4 core
// (BENCHMARKS.md); memory about 30 floats per particle (states twice, weights, scratch).
// Not thread-safe; one filter per session.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/filters/tracker.h"

namespace localizer::engine {

enum class Likelihood { kPeak, kGcc, kMixture };
StatusOr<Likelihood> ParseLikelihood(const std::string& name);  // "peak" | "gcc" | "mixture"
const char* LikelihoodName(Likelihood l);

struct ParticleFilterOptions {
  int particles = 4096;           // N, in [16, 1 << 22]
  double accel_noise_mps2 = 1.0;  // std of the white acceleration, per axis (m/s^2)
  // Velocity mean reversion (particle_set.h Predict): each step keeps exp(-dt / tau) of the
  // velocity; 0 (the default) is constant velocity. Meant for a range the array cannot
  // observe (4 sensors, a source several apertures out), which otherwise runs away:
  // particles heading in meet the array's sharp TDOAs and die, those heading out survive,
  // and the cloud drifts outward at metres per second with every measurement consistent.
  // 10 s acquired 2-5 more of 200 random scenes on each of three campaign draws
  // (ACCURACY.md) but biases the velocity of a truly constant-velocity source towards zero
  // where the TDOAs observe it weakly (particle_filter_test's CV track: vx -0.67 for -1.2
  // m/s, RMSE 0.89 against 0.5 x CRLB), so it is not the default. In [0, 1e6]; > 0 needs
  // turn_rate_max_radps = speed_change_max_mps2 = 0. This filter only: the multiple-model and
  // the GPU particle filters keep constant velocity.
  double velocity_time_constant_s = 0.0;
  // Manoeuvres: a heavy-tailed acceleration of the same RMS, accel_noise_mps2. Each step a
  // share of the particles, drawn afresh, manoeuvre with an acceleration std manoeuvre_scale
  // times the others' (at 0.1 and 10: the quiet ones 0.30 x accel_noise_mps2, the
  // manoeuvring ones 3.0 x). The quiet core averages frames where white acceleration of the
  // RMS follows each frame's noise; the manoeuvring share follows a turn. Off by default: on
  // four random campaign draws (ACCURACY.md, "Manoeuvres") 0.1 / 10 acquired 3-8 more scenes
  // of 200 and halved the named underwater scene's RMSE, but had 3 more silent failures on
  // two draws and tripled tetra-air's (a talker walking an arc 4-8 apertures out: restarts);
  // 0.1 / 4 was neutral. share in [0, 1) (0: plain white acceleration), scale >= 1. The
  // multiple-model filter keeps white acceleration.
  double manoeuvre_share = 0.0;
  double manoeuvre_scale = 10.0;
  // The motion below is the default since the nineteenth pass (ACCURACY.md): each particle
  // carries an acceleration level, a turn rate and a speed change that persist, so that the
  // quiet particles the weights prefer on a steady source can still follow an arc or a source
  // that speeds up. Five 200-scene campaign draws against one std (BENCHMARKS.md, "Issue 15,
  // nineteenth pass"): acquired as reported 987 against 967, within 3 x the theoretical CRLB
  // 443 against 334, p95 time to acquire 5.5-9.1 s against 10.1-11.6, Gaussian RMSE/CRLB
  // 0.53-0.62 against 0.67-0.76, silent failures 6 against 5; the filter 7.5 against 6.0 ns
  // per particle-step, the pipeline 1.97 against 1.72 ms per audio-second.
  // The GPU particle filter runs one std only (SetSingleMotion): with the defaults a session's
  // filter runs on the CPU beside the device GCC.
  //
  // Acceleration levels that persist: each particle carries its own gain on the white
  // acceleration (std = gain x accel_noise_mps2), drawn log-uniform in
  // [accel_level_floor, accel_level_ceiling] at every (re)start and redrawn by each particle
  // at rate accel_level_switch_hz (a jump process); resampling copies a particle's gain with
  // it. The weights then select the level the motion needs: a still source keeps the quiet
  // particles (frames average over seconds), a manoeuvring one the loud ones, and the
  // redraws keep every level alive for the next change. Why: the right single std spans
  // three decades across arrays and motions (a 0.4 m board with millimetre fixes against a
  // 40 m array at sea). Alone, the levels' quiet particles lag a source on an arc along its
  // weakly observed range (tetra-air 0.17 -> 1.15 x CRLB, 1-2 restarts a run: the turn rates
  // below answer it) and a source that keeps accelerating (the speed changes below).
  // floor = ceiling = 1: one std (off). floor in [1e-6, ceiling], ceiling <= 100, switch rate
  // in [0, 1000] Hz. This filter only: the multiple-model filter keeps one std.
  double accel_level_floor = 0.003;
  double accel_level_ceiling = 3.0;
  double accel_level_switch_hz = 1.0;
  bool accel_levels() const { return !(accel_level_floor == 1.0 && accel_level_ceiling == 1.0); }
  // Turn rates that persist: each particle turns its velocity about +z at its own rate,
  // uniform in [-turn_rate_max_radps, turn_rate_max_radps] when drawn and redrawn at
  // accel_level_switch_hz (particle_set.h SetTurnRates), so quiet particles can follow an
  // arc instead of straight lines whose range drifts. In [0, 5] (0: off); needs
  // velocity_time_constant_s = 0. With the levels and without speed changes, five campaign
  // draws gave 503 against 334 scenes within 3 x the theoretical CRLB, but the constant-
  // acceleration path of filter_bounds_test was lagged at 2.1-3.5 x its bound (ACCURACY.md,
  // "Seventeenth pass").
  double turn_rate_max_radps = 1.0;
  // Speed changes that persist: each particle accelerates along its velocity at its own
  // rate, 0 for half the draws (they hold their speed) and uniform in
  // [-speed_change_max_mps2, speed_change_max_mps2] for the others, redrawn at
  // accel_level_switch_hz (particle_set.h SetSpeedChanges). Why: with the levels the quiet
  // particles, turning or not, cannot follow a source that keeps speeding up, and the weights
  // still prefer them (filter_bounds_test's constant-acceleration path: 2.1 x its bound with
  // levels and turn rates; 0.87 x with speed changes up to 1 m/s^2 as well). In [0, 20]
  // (0: off); needs velocity_time_constant_s = 0 (ACCURACY.md, "Nineteenth pass").
  double speed_change_max_mps2 = 1.0;
  // One acceleration std, no turn rates, no speed changes: the motion the GPU particle
  // filter runs (and the default before the nineteenth pass).
  void SetSingleMotion() {
    accel_level_floor = accel_level_ceiling = 1.0;
    turn_rate_max_radps = 0.0;
    speed_change_max_mps2 = 0.0;
  }
  bool single_motion() const { return !accel_levels() && turn_rate_max_radps == 0.0 && speed_change_max_mps2 == 0.0; }
  double tdoa_sigma_s = 0.0;          // TDOA noise std; 0: adaptive (below)
  double peak_dof = 4.0;              // peak likelihood: Student-t degrees of freedom, > 0
  double gcc_sharpness = 1.0;         // GCC likelihood: curvature at the peak / the peak
                                      // likelihood's, > 0
  double outlier_probability = 0.05;  // mixture likelihood: eps, the chance a pair's peak
                                      // is an outlier, in [0, 1)
  // Motion blur (peak and mixture likelihoods; the GCC likelihood reads the smeared GCC
  // itself): a particle whose velocity moves pair p's delay at rate r_p (s/s) within the
  // frame sees that pair's peak spread into a bell of variance r_p^2 V (V =
  // Measurement::window_time_var_s2, 0.02 T^2 for a Hann frame of T s); where the bell's top
  // is flat beside the noise the peak lies anywhere on it, so the particle's likelihood of the
  // pair takes sigma_p^2 + K_p r_p^2 V with K_p = motion_blur x min(1, 2 / peak_snr)
  // (particle_math.h, MotionBlurVariance). Why: a PHAT peak of a delay that moves by tens of
  // samples within a frame is a ridge whose highest ripple has the band's sharpness, and its
  // curvature claims a precision the ridge does not have: a source at 3.35 m/s in 0.34-s
  // frames was tracked 0.25-0.93 m off claiming 0.03-0.15 m for a second. Measured at 1
  // (ACCURACY.md, "Forty-second pass"): thirty campaign draws, summed silent-failure time
  // 13.3 -> 8.6 s and p95 time to acquire -0.25 s, error ratios within their scatter, median
  // NEES per dimension 0.61 -> 0.52; but the named water scenes' RMSE rose by a fifth to a
  // half (a start learns its velocity in 3 s instead of 1: particles with the wrong velocity
  // are judged less sharply), so it is off by default. In [0, 1]; 0: off; a front end that
  // leaves V at 0 turns it off too. The CPU and GPU filters both apply it.
  double motion_blur = 0.0;
  Likelihood likelihood = Likelihood::kPeak;
  double min_peak_snr = 5.0;        // pairs whose peak_snr is below are not used: the
                                    // frame holds no coherent source for them (noise
                                    // alone stays below ~4 at p99)
  double resample_threshold = 0.8;  // resample when ESS < threshold * N (seed: 0.8)
  double kernel_scale = 0.5;        // regularisation after resampling, x Silverman's
                                    // bandwidth (0: plain bootstrap filter)
  int tempered_updates = 2;         // updates after each (re)start applied in 4 tempered
                                    // stages (progressive correction, particle_filter.cc),
                                    // or, when the first would collapse the cloud and one
                                    // label lives (tempering on, below), in up to 12
                                    // ESS-chosen ones; in [0, 100]; the GPU filter has none yet.
                                    // In these updates (tempering on) a label whose cloud
                                    // would collapse on the fix the frame gives near it has
                                    // half its particles redrawn around that fix, weighted
                                    // to keep its predicted density (a two-point start:
                                    // particle_set.h ProposeAroundFixes), and the update
                                    // goes in whole or in ESS-chosen stages
  // Adaptive tempering: an update (after the tempered ones above) whose ESS would fall
  // below this fraction of N is applied in up to 6 stages, each taking the largest share of
  // the likelihood that keeps the ESS near N / 5, with resampling and the kernel move
  // between (particle_filter.cc, AdaptiveUpdate; UpdateReport::likelihood_stages says how
  // many). Why: a likelihood far narrower than the predicted cloud (a near source on a small
  // array: fixes to a fraction of a millimetre against centimetres of white-acceleration
  // spread per frame) otherwise lands on the few particles near its peak, and a wider,
  // wrong mode (the far exact solution of a 4-sensor array) wins on sampling luck.
  // particle_tempering_test: 0.9-1.2 x the per-frame CRLB with it, 3000-16000 x without.
  // Random campaigns (ACCURACY.md, thirteenth pass): neutral with plain PHAT (951 against 957
  // of 1000 acquired, 8 against 10 silent failures); with PHAT-coherence silent 11 -> 6 of 200.
  // While several labels live an update stays one stage (the contender rule, particle_set.h).
  // In [0, 1]; 0: off (one stage always). Only frames that would collapse pay: up to 5
  // extra weighing and resampling passes and 8 ESS evaluations per extra stage.
  double tempering_ess_fraction = 0.05;
  uint64_t seed = 1;

  Status Validate() const;
};

class ParticleFilter final : public Tracker {
 public:
  static StatusOr<std::unique_ptr<ParticleFilter>> Create(const ArrayGeometry& array,
                                                          const ParticleFilterOptions& options);
  ~ParticleFilter() override;
  ParticleFilter(const ParticleFilter&) = delete;
  ParticleFilter& operator=(const ParticleFilter&) = delete;

  bool initialised() const override;
  // Particles ~ N(mean, covariance), weights equal.
  Status Initialise(const TrackState& belief) override;
  // Particles uniform in the box [min_m, max_m] with velocities ~ N(0, speed_sigma_mps^2 I).
  Status InitialiseRegion(const Vec3& min_m, const Vec3& max_m, double speed_sigma_mps) override;
  // Particles split among the components by weight; each keeps its label (particle_set.h).
  Status InitialiseMixture(const std::vector<WeightedBelief>& components) override;
  // Per live component (weight >= 1e-3), heaviest first.
  std::vector<WeightedBelief> Hypotheses() const override;
  void SetBounds(const Vec3& min_m, const Vec3& max_m) override;
  Status SetArray(const ArrayGeometry& array) override;
  void Predict(double dt_s) override;
  StatusOr<UpdateReport> Update(const Measurement& measurement) override;
  TrackState State() const override;

  double ess() const;
  // The TDOA noise std the last update used (0 before the first update).
  double tdoa_sigma_s() const;

 private:
  struct Impl;
  explicit ParticleFilter(std::unique_ptr<Impl> impl);
  // Applies m in up to max_stages stages chosen by the ESS; returns the ESS.
  double AdaptiveUpdate(const Measurement& m, int* stages, int max_stages);
  std::unique_ptr<Impl> impl_;
};

}  // namespace localizer::engine
