// The particle filter's storage and per-particle kernels, float32 structure-of-arrays.
//
// Positions are stored relative to the array centroid (`origin`), so float32 keeps
// micrometre resolution tens of metres away. The per-particle loops run over contiguous
// arrays without branches and are written to vectorise (see -fopenmp-simd in CMakeLists.txt);
// random numbers are counter-based (fast_math.h), keyed by (seed, draw number), and the float
// sums over the particles keep a fixed 8-lane order (lane_sums.h), so results do not depend on
// how the loops are vectorised (256- or 512-bit). Every per-particle array starts on a cache
// line (aligned_vector.h). Internal to engine/filters.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/core/aligned_vector.h"
#include "engine/core/measurement.h"
#include "engine/filters/pair_noise.h"
#include "engine/filters/particle_filter.h"
#include "engine/filters/particle_math.h"
#include "engine/filters/tracker.h"

namespace localizer::engine {

// Gain k of the GCC log-likelihood k * g(lag): matched so that near the main peak
// k * g has the curvature of a Gaussian of sigma_samples (k = sharpness / (sigma^2 * -g'')),
// while away from it every secondary peak keeps its relative height.
double GccGain(const std::vector<float>& gcc, double sigma_samples, double sharpness);

// A lower-triangular root L L^T = covariance (Cholesky, or a triangularised eigen root when
// a dimension has collapsed): the regularisation kernel's shape (particle_resampling.cc).
// Its bandwidth and shrinkage, and the other per-particle formulas: particle_math.h.
Mat6 CovarianceRoot(const Mat6& covariance);

// The gains on a unit normal acceleration draw for quiet and manoeuvring particles:
// quiet = 1 / sqrt(1 - share + share scale^2), manoeuvre = scale x quiet, so that the
// mixture's variance is 1 (the accel_sigma given stays the acceleration's RMS).
struct ManoeuvreGains {
  double quiet = 1.0, manoeuvre = 1.0;
};
ManoeuvreGains ManoeuvreGainsFor(double share, double scale);

// The GCC likelihood reads each pair's GCC upsampled this many times (gcc_upsampling.h).
inline constexpr int kGccUpsampling = 8;

class ParticleSet {
 public:
  ParticleSet(const ArrayGeometry& array, const ParticleFilterOptions& options);

  // The array moved (tracker.h SetArray): sensor positions relative to the set's fixed
  // origin (the first pose's centroid) are recomputed; particles are untouched.
  void SetSensors(const ArrayGeometry& array);
  // x = mean + root z, z ~ N(0, I6); weights equal.
  void SampleGaussian(const Vec6& mean, const Mat6& root);
  // Position uniform in the box, velocity ~ N(0, speed_sigma^2 I3); weights equal.
  void SampleUniformBox(const Vec3& min_m, const Vec3& max_m, double speed_sigma_mps);
  // p += v dt + a dt^2/2, v += a dt, a ~ N(0, accel_sigma^2 I3). With a velocity time
  // constant tau > 0 the velocity is mean-reverting (Ornstein-Uhlenbeck): v' = d v + a dt,
  // p += tau (1 - d) v + a dt^2/2, d = exp(-dt / tau); tau = 0 is constant velocity.
  void Predict(double dt_s, double accel_sigma_mps2, double velocity_time_constant_s = 0.0);
  // Coordinated turn at a fixed rate omega (rad/s, counter-clockwise seen from +z) in the
  // x-y plane, constant vz, plus the same white acceleration as Predict, its normals drawn
  // from `key` (NextKey()): clouds predicted with one key share their noise (common random
  // numbers). With s = sin(omega dt), c = cos(omega dt), a = s / omega, b = (1 - c) / omega
  // (a = dt, b = 0 at omega = 0):
  //   x += a vx - b vy,  y += b vx + a vy,  z += vz dt,  vx' = c vx - s vy,  vy' = s vx + c vy;
  //   then p += acc dt^2/2, v += acc dt.
  void PredictTurn(double dt_s, double turn_rate_radps, double accel_sigma_mps2, uint32_t key);
  // Heavy-tailed acceleration for Predict and PredictTurn (ParticleFilterOptions::
  // manoeuvre_share): each step a share of the particles, drawn afresh, manoeuvre, their
  // acceleration std `scale` times the others'; both are set so that the mixture's variance
  // stays accel_sigma^2 (ManoeuvreGainsFor). share 0 (the default) is plain white
  // acceleration. share in [0, 1), scale >= 1.
  void SetManoeuvre(double share, double scale);
  // Acceleration levels that persist (ParticleFilterOptions::accel_level_*): each particle
  // carries its own gain on the white acceleration, log-uniform in [floor, ceiling] when
  // drawn; a particle redraws its gain at rate switch_rate_hz (a jump process), and
  // resampling copies the gain with the particle. floor = ceiling = 1 (the default): off.
  void SetAccelLevels(double floor, double ceiling, double switch_rate_hz);
  // Turn rates that persist (ParticleFilterOptions::turn_rate_max_radps): each particle
  // carries its own rate omega_i, uniform in [-max, max] when drawn, and Predict turns its
  // velocity about +z by omega_i dt (the coordinated turn of PredictTurn) before the white
  // acceleration; a particle redraws its rate at the levels' switch rate, and resampling
  // copies it. So a source on an arc is followed by quiet particles on the arc, not by
  // straight lines that match its bearings while their range drifts. max = 0: off.
  void SetTurnRates(double max_radps, double switch_rate_hz);
  // Speed changes that persist (ParticleFilterOptions::speed_change_max_mps2): each
  // particle carries its own acceleration along its velocity, 0 for a share kSpeedHoldShare
  // of the draws (they hold their speed) and uniform in [-max, max] for the others; Predict
  // scales the (turned) velocity by max(0, 1 + a_i dt / |v|) and moves the particle by the
  // step's mean velocity. Redrawn at switch_rate_hz and copied by resampling, as the turn
  // rates. So a quiet particle can follow a source that speeds up or slows down. max = 0: off.
  void SetSpeedChanges(double max_mps2, double switch_rate_hz);
  static constexpr float kSpeedHoldShare = 0.5f;
  // A fresh random-stream key per use: hash of (seed, use count).
  uint32_t NextKey();
  // Copies `other`'s particles and weights (same array and particle count; the random
  // stream stays this set's own).
  void CopyCloudFrom(const ParticleSet& other);
  // Particle i becomes particle i of candidates[choice[i]], with log-weight log_weights[i]
  // (the multiple-model filter's per-particle pick among its hypotheses' predictions);
  // then the weights are normalised and the ESS returned, as NormaliseWeights.
  double TakeParticles(const std::vector<const ParticleSet*>& candidates, const std::vector<uint8_t>& choice,
                       std::span<const float> log_weights);
  // Log-weights as last left (normalised after NormaliseWeights), one per particle.
  const AlignedVector<float>& log_weights() const { return logw_; }
  // Normalised linear weights as of the last NormaliseWeights (or sampling, resampling).
  const AlignedVector<float>& weights() const { return w_; }
  // The particles' state, one column per component (x, y, z relative to the set's origin,
  // then vx, vy, vz), n values each: for diagnostics and tests.
  std::array<const float*, 6> columns() const {
    return {cur_.x.data(), cur_.y.data(), cur_.z.data(), cur_.vx.data(), cur_.vy.data(), cur_.vz.data()};
  }
  // After ResampleSystematic: slot m now holds a copy of particle resample_index()[m].
  const AlignedVector<int>& resample_index() const { return index_; }
  // Adds each particle's log-likelihood of `m` to its log-weight (see particle_filter.h) and
  // reports, per pair, the innovation of the peak delay against the prior predicted delays.
  // sigmas_s holds one TDOA noise std per pair; pairs with used[p] == 0 are skipped.
  // `exponent` < 1 tempers the likelihood (log-weights += exponent x log-likelihood).
  // With ParticleFilterOptions::motion_blur, the peak and mixture likelihoods widen by each
  // particle's own delay rates (particle_filter.h); the innovations use sigmas_s alone.
  void Weigh(const Measurement& m, const std::vector<int>& used, Likelihood likelihood,
             const std::vector<double>& sigmas_s, double peak_dof, double gcc_sharpness,
             std::vector<InnovationMoments>* innovations, float exponent = 1.0f);
  // Normalises the weights (log-sum-exp) and returns the ESS = 1 / sum w^2.
  double NormaliseWeights();
  // Adaptive tempering of the last Weigh (its log-likelihoods are kept until the next one):
  // EssIfUntempered(r) is the ESS the weights would have with r x that log-likelihood taken
  // back out, without changing anything; Untemper(r) takes it out and normalises, returning
  // the ESS. So after Weigh(exponent e), Untemper(e - b) leaves the prior's weights times
  // likelihood^b. r in [0, e]. Single label only (labels() <= 1): the labels' evidence
  // (ScoreLabels) is not taken back.
  double EssIfUntempered(float r) const;
  double Untemper(float r);
  // Systematic resampling (one uniform offset, N evenly spaced pointers); weights equal.
  // Then, when kernel_scale > 0, each copy moves by a kernel with Liu & West
  // shrinkage (a regularised particle filter), which keeps the weighted mean and covariance
  // and restores the diversity that resampling removes:
  //     x' = a x + (1 - a) mean + h L z,   a = sqrt(1 - h^2),  L L^T = covariance,
  // z with zero mean and unit covariance (triangular draws from hash bytes, see the .cc)
  // h = kernel_scale * (4 / (N (d + 2)))^(1 / (d + 4)), d = 6 (Silverman's optimal bandwidth).
  //
  // While several labels live, a label the data have not ruled out (a contender: its best
  // particle's log-likelihood, summed over recent updates with decay kContenderDecay, trails
  // the best label's by less than kContenderMarginNats) keeps at least kContenderShare of the
  // particles, with weights that keep its marginal share (so with several labels the weights
  // after resampling are equal within each label, not across them). Why: the marginal evidence of two
  // exact TDOA solutions of a 4-sensor array differs only by how wide each one's predicted
  // TDOAs are (white acceleration spreads the near solution's more), so resampling by it
  // alone drifts towards the far solution, whichever is true, and removes the other before
  // the motion can tell them apart.
  void ResampleSystematic(double kernel_scale);
  static constexpr int kMaxLabels = 16;
  static constexpr int kMaxContenders = 4;  // labels held up at once (heaviest first)
  // A contender's least share of the particles, and of the weight Modes reports: at 0.1 the
  // reported covariance puts the other solution within sqrt(1 / 0.1) = 3.2 sd.
  static constexpr double kContenderShare = 0.1;
  static constexpr float kContenderDecay = 0.9f;  // per update: about ten updates' memory
  static constexpr float kContenderMarginNats = 6.0f;
  static constexpr float kContenderStepNats = 2.0f;  // the most one update adds to a label's deficit
  // Weighted mean and covariance (cached until the particles or weights change).
  TrackState MeanAndCovariance() const;

  // Several position hypotheses (particle_modes.cc). Each particle carries the label of the
  // mixture component it was drawn from; resampling copies labels, and while more than one
  // label lives the kernel move uses each label's own mean and covariance (a kernel sized
  // by the spread between modes would smear them into each other). When resampling leaves
  // one label, the set is single-mode again and runs the vectorised path.
  struct Component {
    double weight = 1.0;  // > 0, relative
    Vec6 mean = Vec6::Zero();
    Mat6 root = Mat6::Zero();  // root root^T = covariance
  };
  // Particles split among the components in proportion to their weights (at least one
  // each, at most kMaxLabels components); weights equal.
  void SampleMixture(const std::vector<Component>& components);
  // Per live label: its total weight, mean and covariance, heaviest first (labels whose weight
  // is below min_weight left out). One entry (the whole cloud) when single-mode. A label the
  // data have not ruled out (see ResampleSystematic) is reported with at least
  // kContenderShare of the weight (after normalisation), however little the marginal
  // evidence leaves it.
  std::vector<WeightedBelief> Modes(double min_weight) const;
  int labels() const { return labels_; }

  // Proposals that look at the measurement (particle_proposal.cc). A label's predicted cloud
  // far wider than the likelihood (the first update after a start: a fix's position with an
  // unknown velocity, decimetres wide after one hop, against TDOAs that place a near source
  // to a millimetre) has almost no particle where the likelihood is: its best particle,
  // which decides whether the label stays a contender, is poor whether the label is right or
  // not, and a wide wrong mode wins.
  // Per live label: its weight, mean and covariance (absolute positions); label 0 when
  // single-mode.
  struct LabelPrior {
    int label = 0;
    double weight = 0.0;
    Vec6 mean = Vec6::Zero();
    Mat6 covariance = Mat6::Zero();
  };
  std::vector<LabelPrior> LabelPriors() const;
  struct FixProposal {
    int label = 0;
    Vec3 position_m = Vec3::Zero();  // absolute
    Mat3 covariance_m2 = Mat3::Identity();
  };
  // For each proposal: a share s (in (0, 1)) of the label's particles is redrawn with the
  // position ~ q = N(fix, covariance) and the velocity from the label's Gaussian prior
  // given that position (a two-point start: the start's position and this fix give it);
  // then every particle of the label has log p(x) - log((1 - s) p(x) + s q(x)) added to its
  // log-weight, p the label's Gaussian position prior. So the label still carries its
  // predicted density and weight (to the Gaussian approximation of its cloud) and now has
  // particles where the likelihood is. Levels, turn rates and labels stay with the slots.
  void ProposeAroundFixes(const std::vector<FixProposal>& proposals, double share);

  // Positions outside [min, max] (sides may be infinite) are impossible: after every
  // sampling and prediction a particle outside is put back on the wall it crossed and its
  // outward velocity removed.
  void SetBounds(const Vec3& min_m, const Vec3& max_m);

 private:
  struct Columns {
    AlignedVector<float> x, y, z, vx, vy, vz;
    void Resize(int n);
    // The six columns in state order (x, y, z, vx, vy, vz).
    std::array<float*, 6> Pointers() { return {x.data(), y.data(), z.data(), vx.data(), vy.data(), vz.data()}; }
  };
  // Fills accel_ with 3N standard normals (see SetManoeuvre), each particle's scaled by its
  // level gain (SetAccelLevels; over a step of dt_s the levels and the turn rates first jump,
  // each at its switch rate).
  void DrawAccelNormals(uint32_t key, double dt_s = 0.0);
  // DrawAccelNormals' jumps of the per-particle levels, turn rates and speed changes over dt_s,
  // then the normals scaled by each particle's level gain.
  void DrawPersistentJumps(uint32_t key, double dt_s);
  // Predict's constant-velocity step with its normals drawn in the same pass (no levels, no
  // manoeuvres, N even): the same values as DrawAccelNormals then the stored-normals loop.
  void PredictConstantVelocity(uint32_t key, float dt, float a_to_p, float a_to_v);
  // Every particle's gain, turn rate and speed change afresh (after sampling).
  void DrawLevels();
  // Sizes turn_ for the turn rates or, with only speed changes on, zeros (PredictPersistentMotion).
  void SizeTurnRates();
  // gain_[m] <- gain_[index_[m]], turn_ and speed_change_ too (after SystematicIndices).
  void CarryLevels();
  // Predict's step with per-particle turn rates and speed changes (turn_ not empty),
  // normals in accel_.
  void PredictPersistentMotion(float dt, float a_to_p, float a_to_v);
  static float SwitchProbability(double rate_hz, double dt_s);  // 1 - exp(-rate dt)
  // Particles [first, end) ~ N(mean, root root^T), normals keyed by (key, 6 i + k).
  void SampleGaussianRange(const Vec6& mean, const Mat6& root, uint32_t key, int first, int end);
  void SetEqualWeights();
  void SystematicIndices();                 // fills index_: the particle each slot copies
  void DrawKernelNoise();                   // fills noise_ with unit-variance kernel draws
  void ResampleModes(double kernel_scale);  // ResampleSystematic while labels_ > 1
  void ApplyBounds();

  int n_;
  uint64_t seed_;
  uint64_t draws_ = 0;
  Vec3 origin_m_;
  std::vector<float> sensor_x_, sensor_y_, sensor_z_;  // relative to origin
  int reference_;
  std::vector<int> pair_sensor_;
  std::vector<float> pair_span_s_;  // 2 max_delay_s per pair: the mixture's uniform width
  float outlier_probability_;
  float motion_blur_;  // ParticleFilterOptions::motion_blur
  float inv_c_;
  Columns cur_, next_;
  AlignedVector<float> logw_, w_;                         // log-weights; normalised linear weights
  AlignedVector<float> r_ref_, vr_ref_, loglik_, delay_;  // scratch for Weigh
  AlignedVector<float> widen_;                            // Weigh's motion blur, n when on
  std::array<AlignedVector<float>, 6> noise_;             // scratch: kernel draws
  AlignedVector<float> accel_;                            // scratch: 3N process-noise normals
  std::vector<float> fine_gcc_;                           // scratch: a pair's GCC upsampled
  AlignedVector<int> index_, first_slot_;                 // scratch for ResampleSystematic
  // SetManoeuvre: the share of particles that manoeuvre each step, and both gains.
  float manoeuvre_share_ = 0.0f, quiet_gain_ = 1.0f, manoeuvre_gain_ = 1.0f;
  // SetAccelLevels: ln floor, ln ceiling, switch rate; gain_ empty while off.
  float log_level_floor_ = 0.0f, log_level_ceiling_ = 0.0f;
  double level_switch_rate_hz_ = 0.0;
  std::vector<float> gain_, next_gain_;
  // SetTurnRates: the largest rate and the redraw rate; turn_ empty while off.
  float turn_max_radps_ = 0.0f;
  double turn_switch_rate_hz_ = 0.0;
  std::vector<float> turn_, next_turn_;
  // SetSpeedChanges: the largest rate and the redraw rate; speed_change_ empty while off
  // (with turn rates off, turn_ then holds zeros: SizeTurnRates).
  float speed_change_max_mps2_ = 0.0f;
  double speed_change_switch_rate_hz_ = 0.0;
  std::vector<float> speed_change_, next_speed_change_;
  std::vector<uint8_t> jumps_;  // scratch for DrawPersistentJumps: which levels jump
  // Weighted mean and covariance of the current particles, computed on demand and kept
  // until the particles or weights change (State() and the regulariser share them).
  mutable TrackState moments_;
  mutable bool moments_valid_ = false;
  std::vector<uint8_t> label_, next_label_;  // mixture component per particle
  int labels_ = 1;                           // components alive (1: single-mode)
  // Per label: the decayed sum of (best log-likelihood of all) - (its best), per update.
  std::array<float, kMaxLabels> label_deficit_{};
  void ScoreLabels(float exponent);  // after Weigh while labels_ > 1
  // Each label's share with the heaviest kMaxContenders contenders raised to kContenderShare
  // and the others scaled down to make room (normalised); which were raised, if asked.
  std::array<double, kMaxLabels> ContenderShares(const std::array<double, kMaxLabels>& weight,
                                                 std::array<bool, kMaxLabels>* raised = nullptr) const;
  // Before resampling with several labels: scales w_ so that contenders get their share of
  // the slots; returns the weight each label carries out (its marginal weight).
  std::array<double, kMaxLabels> HoldContenders(const std::array<double, kMaxLabels>& weight);
  void SetLabelWeights(const std::array<double, kMaxLabels>& weight);  // after resampling
  // Before resampling: a label whose state (position and velocity) lies within one sd of a
  // heavier label's by each one's own covariance (6-D Mahalanobis squared < 6 both ways) has
  // converged onto it and becomes part of it (its particles relabelled; the heavier label's
  // deficit kept). Two exact TDOA solutions that cross pass with different velocities and stay
  // apart. Why: a label started on a wide mode (a far solution with a range spread of tens of
  // metres) can gather on the true one; held up as a contender, it made the estimate report
  // two modes for as long as the track lived. Returns whether any label was merged.
  bool MergeCoincidentLabels(const std::array<double, kMaxLabels>& weight, const std::array<Vec6, kMaxLabels>& mean,
                             const std::array<Mat6, kMaxLabels>& covariance);
  static constexpr double kMinHeldWeight = 1e-6;
  bool Contender(int label) const { return label_deficit_[static_cast<size_t>(label)] < kContenderMarginNats; }
  bool bounded_ = false;
  Eigen::Vector3f bound_lo_, bound_hi_;  // relative to origin_m_
};

// In the tempered updates after a (re)start (particle_filter.cc): for each live label, the
// fix this frame's used pairs give by Gauss-Newton from the label's predicted position; it
// is proposed (ParticleSet::ProposeAroundFixes) where it lies inside the label's prior
// (Mahalanobis distance < 5) and the label's cloud would collapse on it (the ESS share the
// Gaussian prior and fix imply below collapse_fraction). Returns how many labels got one.
// Needs 3 used pairs or more. Cost: a few 3 x 3 solves per label, then one pass over N at
// about 85 ns per particle (two 3 x 3 Gaussian densities in double; BENCHMARKS.md).
int ProposeLocalFixes(ParticleSet* set, const ArrayGeometry& array, const Measurement& m, const std::vector<int>& used,
                      const std::vector<double>& sigmas_s, double collapse_fraction);

}  // namespace localizer::engine
