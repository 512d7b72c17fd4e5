// Initiator: tentative tracks from the measurements no track took, and their confirmation
// by M of N (Stone Soup's initiator role, with its M-of-N tentative-track logic).
//
// Contract. Initiate(z, taken, dt, room, &started), once per scan after association: from
// the measurements z_j with taken[j] == 0, in index order, at most `room` new tracks
// (state x = (p, v), covariance P, history), cleared and filled into `started`:
//   kOnePoint  every free measurement starts one: x = (z, 0), P = diag(R, sigma_v^2 I),
//              sigma_v = initial_speed_sigma_mps (a velocity prior wide enough for the
//              fastest expected target); history: 1 hit, age 1.
//   kTwoPoint  a free measurement is paired with the nearest free measurement of the
//              previous scan within max_speed_mps dt + 3 sqrt(tr R_1 + max tr R_prev)
//              (each previous one pairs once): x = (z_2, (z_2 - z_1) / dt),
//              P = [R_2, R_2 / dt; R_2 / dt, (R_1 + R_2) / dt^2]; history: 2 hits, age 2.
//              Free measurements left unpaired (also those beyond `room`) wait for the next
//              scan, and only for that one; on the first scan (dt <= 0) all wait. Each
//              search looks at most search_budget grid rows and candidates
//              (PointGrid::QueryWithin): the nearest among those seen.
// A started track is confirmed at once when its hits already reach M (M = 1, or M = 2 with
// two-point initiation). Confirm(history), once per scan for every track after its
// TrackHistory::Record: a tentative track becomes confirmed when M of its last N scans
// brought a measurement (track_history.h MofN); confirmation is never withdrawn.
// Deterministic; work arrays persist (no allocation once grown). Not thread-safe.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "engine/tws/cv_kalman.h"
#include "engine/tws/gaussian.h"
#include "engine/tws/point_grid.h"
#include "engine/tws/track_history.h"

namespace localizer::engine::tws {

enum class Initiation { kOnePoint, kTwoPoint };

struct InitiatorOptions {
  Initiation method = Initiation::kOnePoint;
  double initial_speed_sigma_mps = 150.0;  // one-point: velocity prior std per axis, > 0
  double max_speed_mps = 400.0;            // two-point: fastest target to pair for, > 0
  int confirm_hits = 3;                    // M
  int confirm_window = 5;                  // N; 1 <= M <= N <= 32
  int64_t search_budget = 64;              // two-point: work per pairing search (grid rows + candidates)
};

template <int D>
class Initiator {
 public:
  using State = typename Cv<D>::State;
  using Cov = typename Cv<D>::Cov;

  struct Started {
    State x;
    Cov p;
    TrackHistory history;
  };

  explicit Initiator(const InitiatorOptions& options)
      : options_(options), rule_(options.confirm_hits, options.confirm_window) {}

  void Initiate(const std::vector<Gaussian<D>>& measurements, const std::vector<char>& taken, double dt, int room,
                std::vector<Started>* started);

  // Returns whether the track is (now) confirmed.
  bool Confirm(TrackHistory& history) const {
    if (!history.confirmed && rule_.Reached(history)) history.confirmed = true;
    return history.confirmed;
  }

  const MofN& rule() const { return rule_; }
  // Two-point: the free measurements of the latest scan, waiting to be paired.
  int waiting() const { return static_cast<int>(candidates_.size()); }

 private:
  void Start(const State& x, const Cov& p, int hits, std::vector<Started>* started) const;

  InitiatorOptions options_;
  MofN rule_;
  // Two-point: the previous scan's free measurements.
  std::vector<Gaussian<D>> candidates_, next_candidates_;
  std::vector<Eigen::Vector2d> candidate_xy_;
  std::vector<char> candidate_used_;
  double max_candidate_r_trace_ = 0.0;
  PointGrid candidate_grid_;
};

}  // namespace localizer::engine::tws
