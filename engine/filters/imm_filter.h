// Interacting multiple model filter (Blom & Bar-Shalom 1988; Bar-Shalom, Li &
// Kirubarajan 11.6): K mode-matched Kalman filters (kalman_filter.h, all EKF or all UKF,
// one motion model each) and a Markov chain over which mode is active.
//
// Modes (ImmOptions.modes; default "cv" + "ct"): e.g. constant velocity with low
// acceleration noise and a coordinated turn with a turn-rate state (coordinated_turn.h).
// Switching: pi_ij = P(mode j now | mode i before), pi_ii = stay_probability (0.95), the
// rest spread evenly (model_switching.h).
//
// Predict(dt), one IMM cycle's first half:
//   mixing probabilities  cbar_j = sum_i pi_ij mu_i,   mu_{i|j} = pi_ij mu_i / cbar_j
//   mixed prior of mode j x0_j = sum_i mu_{i|j} x_i^(j),
//                         P0_j = sum_i mu_{i|j} (P_i^(j) + (x_i^(j) - x0_j)(x_i^(j) - x0_j)^T)
//   where x_i^(j), P_i^(j) is mode i's estimate in mode j's state space. Modes share the
//   (p, v) block; a mode's extra entries (turn rate, acceleration) mean something only to
//   modes of the same motion model. So: same model -> mode i's full state; otherwise
//   mode i's (p, v) block, with mode j's own extra entries (mean and their covariance
//   block, uncorrelated with (p, v)) appended (Granstrom, Willett & Bar-Shalom 2015,
//   "unbiased mixing"): the turn-rate estimate of a CT mode is not pulled to 0 by a CV
//   mode that has no turn rate to offer.
//   then each mode predicts (its own F, Q) and mu <- cbar (the predicted probabilities).
// Update(frame), the second half:
//   each mode updates on the frame (same pairs; own gate, own adaptive TDOA noise) and
//   gives its likelihood L_j = N(nu_j; 0, S_j) (KalmanFilter::last_log_likelihood);
//   mu_j <- L_j mu_j / sum_i L_i mu_i.
// Gated frames: a mode whose gate refuses the frame keeps its prediction but its
// likelihood still counts (a CV mode that gates the start of a turn loses probability to
// the turn mode that accepts it); when every mode refuses, mu is unchanged and the report
// says gated. A frame with no usable pair changes nothing.
// Estimate: the moment-matched mixture over the common (p, v) block,
//     x = sum_j mu_j x_j,   P = sum_j mu_j (P_j + (x_j - x)(x_j - x)^T).
// Report: nis, tdoa_sigma_s of the most probable mode after the update; ess 0.
//
// Cost per step: K Kalman steps plus the mixing, O(K^2 n^2) with n <= 9: cv + ct with 7
// pairs takes ~15 us (EKF modes) or ~24 us (UKF) per predict + update + estimate on one
// 2.6 GHz core, 3x one EKF step (tests/bench/kalman_bench.cc). Not thread-safe; one
// filter per session.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/filters/kalman_filter.h"
#include "engine/filters/tracker.h"

namespace localizer::engine {

struct ImmMode {
  std::string name;  // reported in ModelProbabilities; "" -> the motion model's name
  MotionModelKind motion_model = MotionModelKind::kCv;
  MotionModelOptions motion;
};

// The modes' motion models from a comma-separated list (e.g. "cv,ct" on the wire and in
// flags), in order; INVALID_ARGUMENT naming `field` for an empty list, an empty entry, a
// name that is not a motion model or one named twice.
StatusOr<std::vector<MotionModelKind>> ParseImmModes(const std::string& list, const std::string& field);
std::string ImmModesName(const std::vector<MotionModelKind>& modes);  // "cv,ct"

struct ImmOptions {
  // The mode filters' shared options: variant (EKF/UKF), TDOA noise, pair selection,
  // gate, robust update, initial std of extra states. Its motion_model and motion are
  // replaced by each mode's.
  KalmanOptions kalman;
  std::vector<ImmMode> modes = {{"cv", MotionModelKind::kCv, {}},
                                {"ct", MotionModelKind::kCt, {}}};  // >= 1, <= 8, unique names
  double stay_probability = 0.95;                                   // pi_ii, in [0, 1]

  Status Validate() const;  // INVALID_ARGUMENT naming the field
};

class ImmFilter final : public Tracker {
 public:
  static StatusOr<std::unique_ptr<ImmFilter>> Create(const ArrayGeometry& array, const ImmOptions& options);
  ~ImmFilter() override;
  ImmFilter(const ImmFilter&) = delete;
  ImmFilter& operator=(const ImmFilter&) = delete;

  bool initialised() const override;
  // Every mode starts from the belief (extra entries 0 with kalman.extra_state_std);
  // mode probabilities uniform.
  Status Initialise(const TrackState& belief) override;
  Status SetArray(const ArrayGeometry& array) override;
  void Predict(double dt_s) override;
  StatusOr<UpdateReport> Update(const Measurement& measurement) override;
  TrackState State() const override;
  std::vector<ModelProbability> ModelProbabilities() const override;

  const KalmanFilter& mode(int j) const;

 private:
  struct Impl;
  explicit ImmFilter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace localizer::engine
