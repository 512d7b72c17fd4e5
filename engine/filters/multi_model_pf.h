// Multiple-model particle filter (the seed's): several state equations run side by side on
// one particle cloud; for each particle the prediction that best matches the frame is the
// one most likely kept, so a sudden manoeuvre is followed by the hypothesis that explains it.
//
// State per particle: (x, y, z, vx, vy, vz) in m and m/s, as the particle filter
// (particle_filter.h; storage, likelihoods and resampling are its ParticleSet's), plus the
// hypothesis m_i it last kept.
//
// Hypotheses k = 1..K (ParticleMotion): a coordinated turn at a fixed rate omega_k
// (rad/s, counter-clockwise seen from +z; 0: constant velocity) with white acceleration
// a ~ N(0, sigma_k^2 I3) (ParticleSet::PredictTurn):
//     x += (s vx - (1 - c) vy) / omega + a dt^2/2,   vx' = c vx - s vy + a dt,
//     y += ((1 - c) vx + s vy) / omega + a dt^2/2,   vy' = s vx + c vy + a dt,
//     z += vz dt + a dt^2/2,  vz' = vz + a dt,        s = sin(omega dt), c = cos(omega dt).
// DefaultParticleMotions(sigma): "cv" (sigma), "cv-manoeuvre" (4 sigma), "ct-left"
// (+0.1 rad/s, sigma), "ct-right" (-0.1 rad/s, sigma).
// Switching prior: pi(j, k) = stay_probability for k = j, (1 - stay_probability)/(K - 1)
// otherwise (model_switching.h).
//
// Predict(dt): every particle is propagated under every hypothesis with the same noise
// draw (common random numbers, so the candidates x_i^k differ by their models only). Until
// an update, particle i takes the candidate of a hypothesis drawn from pi(m_i, .).
// Update(frame), with the particle filter's likelihood l (same pairs, same per-pair sigmas):
//     alpha_ik = w_i pi(m_i, k) l(z | x_i^k)
// particle i keeps candidate k with probability alpha_ik / sum_k alpha_ik (the best match
// is the likeliest pick) and its weight becomes sum_k alpha_ik, the frame's likelihood
// marginalised over the hypothesis: an exact importance-sampling step for the pair
// (hypothesis, state). Model probabilities: the normalised marginal likelihoods
//     mu_k = sum_i alpha_ik / sum_ij alpha_ij,
// smoothed by pi through the labels (after Predict: mu_k = sum_i w_i pi(m_i, k)). Then the
// weights are normalised, and the cloud resampled (labels follow their particles) as the
// particle filter's; the NIS and the adaptive TDOA noise read the innovations of the
// hypothesis most probable before the update. A frame with no usable pair keeps the
// prediction.
// Why each particle picks, not the cloud as a whole: at 20 frames/s a 0.1 rad/s turn moves
// a one-step prediction by ~0.1 mm, far below what one frame's TDOAs resolve, so a
// whole-cloud choice would be a coin toss every frame; labels that persist let a
// hypothesis gather evidence over many frames through resampling (the multiple-model
// bootstrap filter of McGinnity & Irwin 2000), while a manoeuvre that one step does reveal
// is taken up at once. Why a draw, not the arg max: with the stay prior a label would
// almost never change on one frame's evidence, and hypotheses not winning now would die
// out at resampling, leaving none to take over when the manoeuvre starts.
//
// Cost per step: K particle predictions and weighings plus O(N K) for the picks: about
// K times the particle filter's (4 hypotheses, 7 pairs: 4.1x, 69 ns per particle on one
// 2.6 GHz core; tests/bench/kalman_bench.cc); memory K + 1 particle sets (about
// 30 (K + 1) floats per particle). Not thread-safe; one filter per session.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/filters/particle_filter.h"
#include "engine/filters/tracker.h"

namespace localizer::engine {

struct ParticleMotion {
  std::string name;               // reported in ModelProbabilities, unique, non-empty
  double accel_noise_mps2 = 1.0;  // std of the white acceleration per axis, >= 0
  double turn_rate_radps = 0.0;   // fixed turn rate, + counter-clockwise; 0: constant velocity
};

// The default hypotheses for a white-acceleration std `accel_noise_mps2` (above).
std::vector<ParticleMotion> DefaultParticleMotions(double accel_noise_mps2, double turn_rate_radps = 0.1);

struct MultiModelPfOptions {
  ParticleFilterOptions particle;      // N, likelihood, TDOA noise, resampling, seed (its
                                       // accel_noise_mps2 is unused: each hypothesis has its own)
  std::vector<ParticleMotion> models;  // >= 1, <= 16; empty: DefaultParticleMotions(
                                       // particle.accel_noise_mps2)
  double stay_probability = 0.95;      // Markov prior per step, in [0, 1] (1 with K = 1)

  Status Validate() const;  // INVALID_ARGUMENT naming the field
};

class MultiModelParticleFilter final : public Tracker {
 public:
  static StatusOr<std::unique_ptr<MultiModelParticleFilter>> Create(const ArrayGeometry& array,
                                                                    const MultiModelPfOptions& options);
  ~MultiModelParticleFilter() override;
  MultiModelParticleFilter(const MultiModelParticleFilter&) = delete;
  MultiModelParticleFilter& operator=(const MultiModelParticleFilter&) = delete;

  bool initialised() const override;
  // Particles ~ N(mean, covariance), weights equal; hypotheses dealt out evenly (particle
  // i gets i mod K), so mu starts uniform.
  Status Initialise(const TrackState& belief) override;
  // Particles uniform in the box, velocities ~ N(0, speed_sigma_mps^2 I); mu as above.
  Status InitialiseRegion(const Vec3& min_m, const Vec3& max_m, double speed_sigma_mps) override;
  Status SetArray(const ArrayGeometry& array) override;
  void Predict(double dt_s) override;
  StatusOr<UpdateReport> Update(const Measurement& measurement) override;
  TrackState State() const override;
  std::vector<ModelProbability> ModelProbabilities() const override;

  int model_count() const;

 private:
  struct Impl;
  explicit MultiModelParticleFilter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace localizer::engine
