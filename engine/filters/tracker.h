// The tracker interface every filter implements: particle filter, EKF/UKF, IMM and the
// multiple-model particle filter.
#pragma once

#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/core/estimate.h"
#include "engine/core/measurement.h"
#include "engine/core/status.h"
#include "engine/core/types.h"

namespace localizer::engine {

struct TrackState {
  Vec6 mean = Vec6::Zero();  // (x, y, z, vx, vy, vz): m, m/s
  Mat6 covariance = Mat6::Zero();
};

// One component of a belief with several hypotheses: its probability and its Gaussian.
struct WeightedBelief {
  double weight = 1.0;
  TrackState belief;
};

// What one update tells the caller about the fit of model and measurement.
struct UpdateReport {
  // Normalised innovation squared of the pairs' peak TDOAs against the predicted
  // measurement distribution: sum_p (d_p - E[h_p])^2 / (sigma_p^2 + Var[h_p]).
  // ~ chi-square with `pair_count` degrees of freedom when the filter is consistent.
  double nis = 0.0;
  // The NIS's terms per used pair (particle filter; empty from the Kalman filters): the
  // squared innovation and its two variances, noise sigma_p^2 and the state's Var[h_p]
  // (innovation_consistency.h splits the disagreement between them).
  struct NisTerm {
    double innovation2_s2 = 0.0;
    double noise_var_s2 = 0.0;
    double predicted_var_s2 = 0.0;
  };
  std::vector<NisTerm> nis_terms;
  // The same with each pair's noise anchored to its own peak (pair_noise.h), each pair's
  // term capped at 36 (6 sigma: one impulsive outlier cannot fill the divergence window): the
  // divergence test's input, which noise adaptation cannot inflate.
  double anchored_nis = 0.0;
  // Per pair, the signed anchored innovation e / sqrt(anchor^2 + Var[h']), capped at +-6;
  // NaN for pairs the update did not use. The divergence test looks for a persistent bias.
  std::vector<double> anchored_z;
  int pair_count = 0;         // pairs used (those that heard a source); 0: the update did nothing
  double ess = 0.0;           // effective sample size after the update (0 for non-particle filters)
  int likelihood_stages = 1;  // particle filter: stages the likelihood was applied in (tempering)
  double tdoa_sigma_s = 0.0;  // TDOA noise std the update assumed
  // The gate refused the frame (Kalman filters): the state is unchanged, but nis and
  // pair_count still describe it, so a run of refused frames trips the divergence test.
  bool gated = false;
};

// INVALID_ARGUMENT unless [min_m, max_m] is a finite box with min <= max and speed_sigma >= 0.
inline Status ValidateRegion(const Vec3& min_m, const Vec3& max_m, double speed_sigma_mps) {
  if (!min_m.allFinite() || !max_m.allFinite() || (max_m - min_m).minCoeff() < 0.0 || !(speed_sigma_mps >= 0.0)) {
    return InvalidArgument("initial region must be a finite box with min <= max and speed sigma >= 0");
  }
  return Status::Ok();
}

// OK when `moved` is `current`'s array in another pose (same sensor count, reference and
// sound speed, the same distances between sensors to 1 mm); INVALID_ARGUMENT naming what differs.
Status ValidateMovedArray(const ArrayGeometry& current, const ArrayGeometry& moved);

// A root R with R R^T = belief.covariance that tolerates semi-definite covariances
// (V sqrt(max(eigenvalues, 0))); INVALID_ARGUMENT when the mean or covariance is not finite
// or the covariance is not positive semi-definite. Particle filters sample x = mean + R z.
StatusOr<Mat6> BeliefRoot(const TrackState& belief);

class Tracker {
 public:
  virtual ~Tracker() = default;

  virtual bool initialised() const = 0;
  // (Re)start from a Gaussian belief. INVALID_ARGUMENT if mean/covariance are not finite
  // or the covariance is not positive semi-definite.
  virtual Status Initialise(const TrackState& belief) = 0;
  // (Re)start knowing only that the source is inside the box [min_m, max_m] with velocity
  // ~ N(0, speed_sigma_mps^2 I). The default matches the box's mean and covariance with a
  // Gaussian; a particle filter samples the box itself.
  virtual Status InitialiseRegion(const Vec3& min_m, const Vec3& max_m, double speed_sigma_mps) {
    LOCALIZER_RETURN_IF_ERROR(ValidateRegion(min_m, max_m, speed_sigma_mps));
    TrackState belief;
    belief.mean.head<3>() = 0.5 * (min_m + max_m);
    belief.covariance.topLeftCorner<3, 3>() = ((max_m - min_m).array().square() / 12.0).matrix().asDiagonal();
    belief.covariance.bottomRightCorner<3, 3>() = speed_sigma_mps * speed_sigma_mps * Mat3::Identity();
    return Initialise(belief);
  }
  // (Re)start from a mixture of Gaussian beliefs (acquisition's modes: the positions the
  // data allows), weights > 0. A particle filter keeps every component and lets the
  // measurements and the dynamics decide; the default (Kalman-family filters) starts from
  // the heaviest. INVALID_ARGUMENT for an empty list or a bad component.
  virtual Status InitialiseMixture(const std::vector<WeightedBelief>& components) {
    if (components.empty()) return InvalidArgument("mixture initialisation needs at least one component");
    size_t best = 0;
    for (size_t i = 1; i < components.size(); ++i) {
      if (components[i].weight > components[best].weight) best = i;
    }
    return Initialise(components[best].belief);
  }
  // The hypotheses the belief holds, heaviest first, weights summing to 1: several while a
  // particle filter keeps more than one mode alive, else one (the whole belief).
  virtual std::vector<WeightedBelief> Hypotheses() const { return {WeightedBelief{1.0, State()}}; }
  // Positions outside the box [min_m, max_m] (sides may be infinite) are impossible. The
  // default does nothing (Kalman-family filters: the session clamps the acquisition's
  // fixes instead).
  virtual void SetBounds(const Vec3& min_m, const Vec3& max_m) {
    (void)min_m;
    (void)max_m;
  }
  // Propagate the belief by dt_s >= 0 seconds with the motion model.
  virtual void Predict(double dt_s) = 0;
  // Condition on one frame's TDOAs (FAILED_PRECONDITION before Initialise;
  // INVALID_ARGUMENT if the pair count differs from the array's).
  virtual StatusOr<UpdateReport> Update(const Measurement& measurement) = 0;
  virtual TrackState State() const = 0;
  // The array moved (a platform carrying it rotated or travelled): later updates use these
  // sensor positions; the belief is untouched. `array` must have the same sensors,
  // reference and sound speed in another pose (ArrayGeometry::Moved); INVALID_ARGUMENT
  // otherwise. FAILED_PRECONDITION from trackers whose array is fixed at creation (the
  // GPU particle filter keeps its sensors on the device).
  virtual Status SetArray(const ArrayGeometry& array) {
    (void)array;
    return FailedPrecondition("this tracker cannot follow a moving array");
  }
  // The track was taken elsewhere (a HandoffTracker restarted on its other filter): this
  // tracker will not be stepped again until its next initialisation. A batched tracker stops
  // counting on its work (the GPU filter leaves its dispatcher's producers, who would
  // otherwise be waited for every batch). The default does nothing.
  virtual void Suspend() {}
  // Multiple-model trackers: each motion hypothesis and its current probability (summing
  // to 1; after Predict the predicted, after Update the posterior probabilities). Empty
  // for single-model filters.
  virtual std::vector<ModelProbability> ModelProbabilities() const { return {}; }
};

}  // namespace localizer::engine
