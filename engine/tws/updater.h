// Updater: one track's constant-velocity Kalman filter through a scan (cv_kalman.h holds
// the maths; Stone Soup's KalmanPredictor and KalmanUpdater roles in one class, because the
// steady-state form below ties the two together).
//
// Contract, per track and per scan, in this order:
//   Predict(f, dt)   the time update to the scan's instant; dt <= 0 leaves f unchanged.
//   Expected(f)      what the track expects to be measured, (H x, H P H^T) with H = [I 0]:
//                    the predicted position and its covariance, for the associator.
//   Update(f, z, dt) the measurement update with z (mean, covariance R), when the associator
//                    gave the track a measurement; or
//   Miss(f)          when it gave none (the track coasts on its prediction).
// Start(x, P) makes a filter from an initiator's state and covariance.
//
// Forms (UpdaterOptions::form):
//   kKalman       the full update every scan: S = A + R, K = [A; B^T] S^-1, P <- P - K S K^T.
//   kSteadyState  the same until the gain converges (the largest change of any entry between
//                 two consecutive updates <= steady_state_tolerance x the largest entry, both
//                 updates at dt > 0), then frozen: the gain, the predicted and the updated
//                 covariance are kept and each scan costs one constant-gain update (the
//                 seed's DSP form, steady_state_gain.h). A miss, or a scan interval other
//                 than the frozen one (relative 1e-9), unfreezes it.
// Deterministic, no allocation, no state besides the options: one updater serves every track.
// Header-only: Predict and Update run once per track per scan and are forced inline into the
// tracker's loop, as they were before the roles were split out of it; GCC's FMA contraction
// follows the inlining, so the tracker's numbers stay the same bit for bit (and the call
// costs nothing).
#pragma once

#include <cmath>

#include "engine/tws/cv_kalman.h"
#include "engine/tws/gaussian.h"

namespace localizer::engine::tws {

enum class FilterForm { kKalman, kSteadyState };

struct UpdaterOptions {
  double accel_noise_mps2 = 5.0;  // sigma_a of the white-acceleration model, >= 0
  FilterForm form = FilterForm::kKalman;
  double steady_state_tolerance = 1e-3;  // in (0, 1)
};

// One track's filter: state, covariance, and the steady-state bookkeeping.
// (The flags come last: the Eigen members are 64-byte aligned under AVX-512, and a flag
// between them would pad the struct by a cache line.)
template <int D>
struct FilterState {
  using K = Cv<D>;
  typename K::State x;
  typename K::Cov p;
  typename K::Gain last_gain = K::Gain::Zero();  // the previous update's gain
  typename K::Gain frozen_gain;                  // kSteadyState, once converged:
  typename K::Cov frozen_predicted, frozen_updated;
  double frozen_dt = 0.0;
  bool have_last_gain = false;  // set by an update, cleared by a miss
  bool frozen = false;          // kSteadyState, converged
};

template <int D>
class KalmanUpdater {
 public:
  using K = Cv<D>;
  using State = typename K::State;
  using Cov = typename K::Cov;

  explicit KalmanUpdater(const UpdaterOptions& options)
      : options_(options), q_(options.accel_noise_mps2 * options.accel_noise_mps2) {}

  static FilterState<D> Start(const State& x, const Cov& p) {
    FilterState<D> f;
    f.x = x;
    f.p = p;
    return f;
  }

  [[gnu::always_inline]] void Predict(FilterState<D>& f, double dt) const {
    if (dt <= 0.0) return;
    K::PredictState(f.x, dt);
    if (f.frozen && std::abs(dt - f.frozen_dt) <= 1e-9 * f.frozen_dt) {
      f.p = f.frozen_predicted;
    } else {
      f.frozen = false;
      K::PredictCov(f.p, dt, q_);
    }
  }

  static Gaussian<D> Expected(const FilterState<D>& f) {
    return {f.x.template head<D>(), f.p.template topLeftCorner<D, D>()};
  }

  [[gnu::always_inline]] void Update(FilterState<D>& f, const Gaussian<D>& z, double dt) const {
    if (f.frozen) {
      K::UpdateConstantGain(f.x, f.frozen_gain, z.mean);
      f.p = f.frozen_updated;
      return;
    }
    const Cov predicted = f.p;
    const typename K::Gain gain = K::Update(f.x, f.p, z.mean, z.covariance);
    if (options_.form == FilterForm::kSteadyState && f.have_last_gain && dt > 0.0) {
      const double change = (gain - f.last_gain).cwiseAbs().maxCoeff();
      if (change <= options_.steady_state_tolerance * gain.cwiseAbs().maxCoeff()) {
        f.frozen = true;
        f.frozen_gain = gain;
        f.frozen_predicted = predicted;
        f.frozen_updated = f.p;
        f.frozen_dt = dt;
      }
    }
    f.last_gain = gain;
    f.have_last_gain = true;
  }

  static void Miss(FilterState<D>& f) {
    f.frozen = false;  // the steady state assumed a measurement every scan
    f.have_last_gain = false;
  }

  // The largest variance of the position (m^2): what the deleter bounds.
  static double LargestPositionVariance(const FilterState<D>& f) {
    return f.p.template topLeftCorner<D, D>().diagonal().maxCoeff();
  }

  const UpdaterOptions& options() const { return options_; }

 private:
  UpdaterOptions options_;
  double q_;  // sigma_a^2
};

}  // namespace localizer::engine::tws
