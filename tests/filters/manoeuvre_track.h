// A target that flies straight and then turns: the scene on which the multiple-model
// filters must beat their single-model counterparts (imm_filter_test, multi_model_pf_test,
// tests/bench/kalman_bench). Truth comes from geometry, not from any filter's model.
//
// Array: 8 sensors on the corners of a 2 x 2 x 1.6 m box (7 pairs), c = 1500 m/s.
// Target: from (-6, -5, 0.5) m at (1, 0, 0) m/s, straight for straight_s, then a
// coordinated turn at turn_rate_radps (counter-clockwise seen from +z; radius 10 m at
// 0.1 rad/s) for turn_s; vz = 0. Ranges 5-10 m. One frame every dt_s = 50 ms.
// TDOAs: the exact delays at the instant the filters model (the half-delay timing
// correction to first order, as kalman_filter_test), plus N(0, sigma_s^2) noise, sigma
// 2 us (~0.1 sample at 48 kHz), from std::mt19937_64 seeded by `seed`.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/core/measurement.h"
#include "engine/filters/tracker.h"

namespace localizer::engine::testing {

struct ManoeuvreScene {
  double straight_s = 6.0;
  double turn_s = 12.0;
  double turn_rate_radps = 0.1;
  double dt_s = 0.05;
  double sigma_s = 2e-6;
  double sample_rate_hz = 48000.0;
  int steps() const { return static_cast<int>(std::lround((straight_s + turn_s) / dt_s)); }
  int first_turn_step() const { return static_cast<int>(std::lround(straight_s / dt_s)); }
};

inline ArrayGeometry BoxArray() {
  std::vector<Vec3> sensors;
  for (int i = 0; i < 8; ++i) sensors.emplace_back(i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 0.8 : -0.8);
  return *ArrayGeometry::Create(sensors, 1500.0);
}

struct TruthStep {
  Vec3 position_m, velocity_mps;
  Measurement measurement;
};

// A frame of TDOAs for a source at p moving at v: the exact delays at the instant the
// filters model (d = T - (d/2) grad T . v, to first order) plus a draw of `noise` per pair.
inline Measurement TdoaFrame(const ArrayGeometry& array, const Vec3& p, const Vec3& v, double t_s,
                             std::normal_distribution<double>& noise, std::mt19937_64& rng,
                             double sample_rate_hz = 48000.0) {
  Measurement m;
  m.t_s = t_s;
  m.sample_rate_hz = sample_rate_hz;
  const Eigen::VectorXd tdoa = array.Tdoa(p);
  const Eigen::MatrixXd j = array.TdoaJacobian(p);
  for (int k = 0; k < array.pair_count(); ++k) {
    PairMeasurement pair;
    pair.sensor = array.sensor_of_pair(k);
    pair.delay_s = tdoa(k) / (1.0 + 0.5 * j.row(k).dot(v)) + noise(rng);
    pair.peak_snr = 50.0;
    pair.quality = 10.0;
    m.pairs.push_back(pair);
  }
  return m;
}

// The truth and the frame of every step: step k is at t = (k + 1) dt.
inline std::vector<TruthStep> MakeManoeuvre(const ArrayGeometry& array, const ManoeuvreScene& scene, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, scene.sigma_s);
  Vec3 p(-6.0, -5.0, 0.5), v(1.0, 0.0, 0.0);
  std::vector<TruthStep> out;
  const double dt = scene.dt_s;
  for (int step = 0; step < scene.steps(); ++step) {
    const double w = step >= scene.first_turn_step() ? scene.turn_rate_radps : 0.0;
    const double c = std::cos(w * dt), s = std::sin(w * dt);
    p += w == 0.0 ? Vec3(v * dt)
                  : Vec3((s * v.x() - (1 - c) * v.y()) / w, ((1 - c) * v.x() + s * v.y()) / w, v.z() * dt);
    v = Vec3(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z());
    out.push_back({p, v, TdoaFrame(array, p, v, (step + 1) * dt, noise, rng, scene.sample_rate_hz)});
  }
  return out;
}

// The belief a tracker starts from: a track already held (the manoeuvre, not the
// acquisition, is under test): the true start 1 std off on every axis, pos_std_m and
// vel_std_mps.
inline TrackState StartBelief(double pos_std_m = 0.02, double vel_std_mps = 0.05) {
  TrackState b;
  b.mean << -6.0 + pos_std_m, -5.0 - pos_std_m, 0.5 + pos_std_m, 1.0 - vel_std_mps, vel_std_mps, 0.0;
  b.covariance.topLeftCorner<3, 3>() = pos_std_m * pos_std_m * Mat3::Identity();
  b.covariance.bottomRightCorner<3, 3>() = vel_std_mps * vel_std_mps * Mat3::Identity();
  return b;
}

struct ManoeuvreScore {
  double rmse_m = 0.0;                                       // position, from 1 s on (the start transient left out)
  double turn_rmse_m = 0.0;                                  // position, during the turn only
  std::vector<std::vector<ModelProbability>> probabilities;  // per step, after the update
};

// Runs `tracker` over the scene (Predict(dt), Update per step) and scores it.
inline ManoeuvreScore RunManoeuvre(Tracker& tracker, const ManoeuvreScene& scene, const std::vector<TruthStep>& truth) {
  ManoeuvreScore score;
  if (!tracker.Initialise(StartBelief()).ok()) return {1e9, 1e9, {}};
  double sum = 0.0, turn_sum = 0.0;
  int n = 0, turn_n = 0;
  const int skip = static_cast<int>(std::lround(1.0 / scene.dt_s));
  for (int step = 0; step < static_cast<int>(truth.size()); ++step) {
    tracker.Predict(scene.dt_s);
    if (!tracker.Update(truth[step].measurement).ok()) return {1e9, 1e9, {}};
    score.probabilities.push_back(tracker.ModelProbabilities());
    const double e2 = (tracker.State().mean.head<3>() - truth[step].position_m).squaredNorm();
    if (step >= skip) sum += e2, ++n;
    if (step >= scene.first_turn_step()) turn_sum += e2, ++turn_n;
  }
  score.rmse_m = std::sqrt(sum / n);
  score.turn_rmse_m = std::sqrt(turn_sum / turn_n);
  return score;
}

// Mean probability of `model` over steps [from, to).
inline double MeanProbability(const ManoeuvreScore& s, const std::string& model, int from, int to) {
  double sum = 0.0;
  for (int k = from; k < to; ++k) {
    for (const ModelProbability& m : s.probabilities[k]) {
      if (m.model == model) sum += m.probability;
    }
  }
  return sum / (to - from);
}

}  // namespace localizer::engine::testing
